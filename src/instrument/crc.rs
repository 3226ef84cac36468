//! CRC-32 (the IEEE 802.3 / zlib polynomial, reflected, initial value and final XOR 0xFFFF_FFFF: "CRC-32/ISO-HDLC")
//! of link frames and stored records. A 16-entry table (64 bytes of flash), one nibble per step.

/// The reflected polynomial 0x04C1_1DB7.
const POLY_REFLECTED: u32 = 0xEDB8_8320;

/// The CRC of each 4-bit value, for the nibble-wise update.
const NIBBLE_TABLE: [u32; 16] = {
    let mut table = [0u32; 16];
    let mut i = 0;
    while i < 16 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 4 {
            c = if c & 1 != 0 { (c >> 1) ^ POLY_REFLECTED } else { c >> 1 };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

/// A running CRC-32: [`Crc32::update`] with the bytes in order, then [`Crc32::finish`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Crc32::new()
    }
}

impl Crc32 {
    /// A CRC over no bytes yet.
    pub const fn new() -> Crc32 {
        Crc32(0xFFFF_FFFF)
    }

    /// Adds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        let mut c = self.0;
        for &b in bytes {
            c ^= b as u32;
            c = (c >> 4) ^ NIBBLE_TABLE[(c & 0xF) as usize];
            c = (c >> 4) ^ NIBBLE_TABLE[(c & 0xF) as usize];
        }
        self.0 = c;
    }

    /// The CRC of the bytes added.
    pub const fn finish(self) -> u32 {
        self.0 ^ 0xFFFF_FFFF
    }
}

/// The CRC-32 of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(bytes);
    c.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value_of_the_catalogue() {
        // The standard check value of CRC-32/ISO-HDLC: the CRC of the ASCII digits "123456789".
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn running_crc_equals_the_crc_of_the_whole() {
        let data: [u8; 100] = core::array::from_fn(|i| (i * 37 + 11) as u8);
        for split in 0..=data.len() {
            let mut c = Crc32::new();
            c.update(&data[..split]);
            c.update(&data[split..]);
            assert_eq!(c.finish(), crc32(&data), "split at {split}");
        }
        // One flipped bit changes it.
        let mut bad = data;
        bad[50] ^= 0x10;
        assert_ne!(crc32(&bad), crc32(&data));
    }
}
