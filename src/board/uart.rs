//! UART0 of the MPS2 AN386 board (CMSDK APB UART), the host link: receive by interrupt into a byte queue,
//! transmit by polling with a bounded wait. Registers: ARM's CMSDK technical reference manual; base address and
//! interrupt numbers: the AN386 application note (QEMU's `mps2-an386` connects UART0 to its first `-serial`).

use heapless::spsc::Producer;

use crate::instrument::main_loop::LinkTx;

use super::mps2_an386::{read, unmask_irq, write, CLOCK_HZ};

const UART0: usize = 0x4000_4000;
const UART_DATA: usize = 0x00;
const UART_STATE: usize = 0x04;
const UART_CTRL: usize = 0x08;
const UART_INTSTATUS: usize = 0x0C;
const UART_BAUDDIV: usize = 0x10;
/// STATE: transmit buffer full (bit 0), receive buffer full (bit 1), receive overrun (bit 3).
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const STATE_RX_OVERRUN: u32 = 1 << 3;
/// CTRL: transmit enable (bit 0), receive enable (bit 1), receive interrupt enable (bit 3).
const CTRL_TX_RX_RX_IRQ: u32 = 0b1011;
/// INTSTATUS/INTCLEAR: receive interrupt (bit 1), receive overrun (bit 3).
const INT_RX: u32 = 1 << 1;
const INT_RX_OVERRUN: u32 = 1 << 3;

/// UART0's receive interrupt number.
pub const UART0_RX_IRQ: i16 = 0;
/// The link's baud rate.
pub const LINK_BAUD: u32 = 115_200;
/// Length of the receive queue (it holds one byte less): 44 ms of the link at 115200 baud (11.5 bytes per ms),
/// more than four sample periods of the main loop, which empties it every period.
pub const RX_QUEUE_SLOTS: usize = 512;
/// The longest wait for room in the transmit buffer, in polls of its state: at least 0.2 s at 25 MHz (a poll is
/// at least one cycle), thousands of byte times at 115200 baud (87 us each). The wait is that long because under
/// QEMU the transmit buffer stays full until the host end of the socket has read what was sent, which takes
/// host time, not emulated cycles; on a board a host that stops reading costs at most that per byte.
const TX_WAIT_POLLS: u32 = 5_000_000;

/// Sets up UART0 (8N1 at [`LINK_BAUD`]; the divider is the clock over the baud rate) with its receive interrupt,
/// and unmasks the interrupt.
pub fn init() {
    write(UART0 + UART_BAUDDIV, CLOCK_HZ / LINK_BAUD);
    write(UART0 + UART_CTRL, CTRL_TX_RX_RX_IRQ);
    unmask_irq(UART0_RX_IRQ as u16);
}

/// The receive interrupt: the byte into `queue`. Returns whether a byte was lost (queue full or the UART's
/// own overrun). The interrupt is acknowledged before the byte is read: reading DATA lets the next byte in, and
/// its interrupt must not be cleared with this one's.
pub fn on_receive(queue: &mut Producer<'_, u8>) -> bool {
    write(UART0 + UART_INTSTATUS, INT_RX | INT_RX_OVERRUN);
    let state = read(UART0 + UART_STATE);
    let mut lost = state & STATE_RX_OVERRUN != 0;
    if lost {
        write(UART0 + UART_STATE, STATE_RX_OVERRUN);
    }
    if state & STATE_RX_FULL != 0 {
        let byte = read(UART0 + UART_DATA) as u8;
        lost |= queue.enqueue(byte).is_err();
    }
    lost
}

/// Sends `bytes`, waiting for room in the transmit buffer at most `TX_WAIT_POLLS` polls per byte; `false` if a
/// wait ran out (the rest is not sent).
pub fn send(bytes: &[u8]) -> bool {
    for &b in bytes {
        let mut polls = 0;
        while read(UART0 + UART_STATE) & STATE_TX_FULL != 0 {
            polls += 1;
            if polls > TX_WAIT_POLLS {
                return false;
            }
        }
        write(UART0 + UART_DATA, b as u32);
    }
    true
}

/// UART0 as the link's transmitter.
#[derive(Clone, Copy, Debug, Default)]
pub struct Uart0;

impl LinkTx for Uart0 {
    fn send(&mut self, bytes: &[u8]) -> bool {
        send(bytes)
    }
}
