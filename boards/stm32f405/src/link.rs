//! The host link on USART1 (115200 baud, 8N1): bytes received by interrupt into the main loop's queue, replies
//! sent by polling with a bounded wait.

use core::sync::atomic::{AtomicU32, Ordering};

use embedded_hal_nb::serial::{Read, Write};
use heapless::spsc::Producer;
use sinscal::instrument::main_loop::LinkTx;
use stm32f4xx_hal::pac::USART1;
use stm32f4xx_hal::serial::{Rx, Tx};

use crate::clocks::SYSCLK_HZ;

/// The link's baud rate (the workstation's `sinscal device --port` sets the same).
pub const LINK_BAUD: u32 = 115_200;
/// Length of the receive queue (it holds one byte less): 44 ms of the link, more than four sample periods of the
/// main loop, which empties it every period.
pub const RX_QUEUE_SLOTS: usize = 512;
/// Core cycles of one byte on the line (10 bits).
const BYTE_CYCLES: u32 = SYSCLK_HZ / (LINK_BAUD / 10);
/// The longest wait for room in the transmit register, polls (at least one cycle each): at least four byte times.
/// A host that stops reading cannot stall the device: the USART sends regardless (no flow control).
const TX_WAIT_POLLS: u32 = 4 * BYTE_CYCLES;

/// Bytes the receive interrupt lost (queue full, or the USART's overrun or framing errors).
pub static RX_LOST: AtomicU32 = AtomicU32::new(0);

/// The receive interrupt: every byte waiting into `queue`; a lost byte counted in [`RX_LOST`].
pub fn on_receive(rx: &mut Rx<USART1>, queue: &mut Producer<'static, u8>) {
    loop {
        match rx.read() {
            Ok(byte) => {
                if queue.enqueue(byte).is_err() {
                    RX_LOST.fetch_add(1, Ordering::Relaxed);
                }
            }
            Err(nb::Error::WouldBlock) => break,
            // Overrun, framing, noise or parity: the HAL has cleared the flag by reading SR then DR.
            Err(nb::Error::Other(_)) => {
                RX_LOST.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}

/// USART1's transmitter as the link's.
pub struct UsartTx(pub Tx<USART1>);

impl LinkTx for UsartTx {
    fn send(&mut self, bytes: &[u8]) -> bool {
        for &b in bytes {
            let mut sent = false;
            for _ in 0..TX_WAIT_POLLS {
                match self.0.write(b) {
                    Ok(()) => {
                        sent = true;
                        break;
                    }
                    Err(nb::Error::WouldBlock) => {}
                    Err(nb::Error::Other(_)) => return false,
                }
            }
            if !sent {
                return false;
            }
        }
        true
    }
}
