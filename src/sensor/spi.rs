//! An embedded-hal SPI transaction on a port that moves one byte at a time: the operations of
//! `SpiDevice::transaction` written once for every board's SPI device (QEMU's PL022, the STM32F405's SPI1). The
//! board brings the byte exchange (with its bounded waits) and the delay; the chip select stays the board's.

use embedded_hal::spi::Operation;

/// Runs `operations` in order through `exchange` (one byte out, the byte received in), stopping at the first
/// failure. `Transfer` runs as long as the longer of its two buffers (missing write bytes are 0, extra read bytes
/// dropped); `DelayNs` calls `delay_ns`.
pub fn run_operations<E>(
    operations: &mut [Operation<'_, u8>],
    mut exchange: impl FnMut(u8) -> Result<u8, E>,
    mut delay_ns: impl FnMut(u32),
) -> Result<(), E> {
    for op in operations.iter_mut() {
        match op {
            Operation::Write(bytes) => {
                for &b in bytes.iter() {
                    exchange(b)?;
                }
            }
            Operation::Read(bytes) => {
                for b in bytes.iter_mut() {
                    *b = exchange(0)?;
                }
            }
            Operation::Transfer(r, w) => {
                for i in 0..r.len().max(w.len()) {
                    let received = exchange(w.get(i).copied().unwrap_or(0))?;
                    if let Some(rb) = r.get_mut(i) {
                        *rb = received;
                    }
                }
            }
            Operation::TransferInPlace(bytes) => {
                for b in bytes.iter_mut() {
                    *b = exchange(*b)?;
                }
            }
            Operation::DelayNs(ns) => delay_ns(*ns),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A loop-back port that returns each byte plus one and records what it sent.
    #[test]
    fn every_operation_exchanges_its_bytes_in_order() {
        let mut sent = [0u8; 16];
        let mut n = 0;
        let mut delays = 0u32;
        let (mut read, mut transfer_r, mut in_place) = ([0u8; 2], [0u8; 3], [10u8, 20]);
        let mut ops = [
            Operation::Write(&[1, 2]),
            Operation::Read(&mut read),
            Operation::Transfer(&mut transfer_r, &[7]),
            Operation::DelayNs(16_000),
            Operation::TransferInPlace(&mut in_place),
        ];
        let result: Result<(), ()> = run_operations(
            &mut ops,
            |b| {
                sent[n] = b;
                n += 1;
                Ok(b.wrapping_add(1))
            },
            |ns| delays += ns,
        );
        assert_eq!(result, Ok(()));
        assert_eq!(&sent[..n], &[1, 2, 0, 0, 7, 0, 0, 10, 20]);
        assert_eq!((read, transfer_r, in_place, delays), ([1, 1], [8, 1, 1], [11, 21], 16_000));
    }

    /// A failure stops the transaction at that byte.
    #[test]
    fn a_failed_exchange_stops_the_transaction() {
        let mut count = 0;
        let mut ops = [Operation::Write(&[1, 2, 3]), Operation::Write(&[4])];
        let result = run_operations(
            &mut ops,
            |b| {
                count += 1;
                if b == 2 {
                    Err("stuck")
                } else {
                    Ok(0)
                }
            },
            |_| {},
        );
        assert_eq!((result, count), (Err("stuck"), 2));
    }
}
