//! The ADIS burst frame: checksum, decoding to fixed point, encoding (for the emulated device), conversion to SI.

use super::error::AdisError;
use super::registers::*;
use crate::sensor::sample::ImuSample;

/// A decoded burst, before conversion to SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Burst {
    /// DIAG_STAT.
    pub diag_stat: u16,
    /// Gyro x, y, z in 16-bit LSB (fixed point, fraction from the _LOW words).
    pub gyro_lsb: [I16F16; 3],
    /// Accelerometer x, y, z in 16-bit LSB.
    pub accel_lsb: [I16F16; 3],
    /// TEMP_OUT.
    pub temp_raw: i16,
    /// DATA_CNTR.
    pub data_counter: u16,
}

/// The big-endian word at `index`. The two bytes are read as one `[u8; 2]` (one halfword load), not
/// byte by byte.
#[inline(always)]
fn word(bytes: &[u8], index: usize) -> u16 {
    u16::from_be_bytes(bytes[2 * index..2 * index + 2].try_into().unwrap_or([0; 2]))
}

/// The little-endian `u32` at `offset`, read as one `[u8; 4]` (one word load; the Cortex-M4 allows it
/// unaligned). Byte-wise reads would cost four loads and three merges.
#[inline(always)]
fn le_u32(bytes: &[u8], offset: usize) -> u32 {
    u32::from_le_bytes(bytes[offset..offset + 4].try_into().unwrap_or([0; 4]))
}

/// Two 16-bit lanes of byte-pair sums of a little-endian word: `b0 + b1` and `b2 + b3`.
#[inline(always)]
fn byte_pair_lanes(x: u32) -> u32 {
    (x & 0x00FF_00FF) + ((x >> 8) & 0x00FF_00FF)
}

/// The byte sum from its two lanes and the bytes after the last whole word, modulo 2^16.
#[inline(always)]
fn fold_lanes(lanes: u32, tail: u32) -> u16 {
    ((lanes & 0xFFFF) + (lanes >> 16) + tail) as u16
}

/// The 16-bit sum of bytes (the burst checksum).
///
/// Computed four bytes at a time: `(x & 0x00FF00FF) + ((x >> 8) & 0x00FF00FF)` holds two 16-bit lanes
/// of byte-pair sums; with at most 8 words per burst the lanes cannot overflow, and the two lanes added
/// give the byte sum modulo 2^16 (a test compares it with the plain sum).
#[inline(always)]
pub fn checksum(bytes: &[u8]) -> u16 {
    let mut lanes = 0u32;
    let words = bytes.len() / 4;
    for k in 0..words {
        lanes = lanes.wrapping_add(byte_pair_lanes(le_u32(bytes, 4 * k)));
    }
    let tail = bytes[4 * words..].iter().fold(0u32, |s, &b| s + b as u32);
    fold_lanes(lanes, tail)
}

/// [`checksum`] of the 30 bytes before the checksum word of a 32-bit burst, written out word by word
/// (size optimisation keeps a loop rolled; this is the interrupt path).
#[inline(always)]
fn checksum32(f: &[u8; BURST32_LEN]) -> u16 {
    let w = |offset: usize| byte_pair_lanes(le_u32(f, offset));
    fold_lanes(w(0) + w(4) + w(8) + w(12) + w(16) + w(20) + w(24), f[28] as u32 + f[29] as u32)
}

/// [`checksum`] of the 18 bytes before the checksum word of a 16-bit burst, written out.
#[inline(always)]
fn checksum16(f: &[u8; BURST16_LEN]) -> u16 {
    let w = |offset: usize| byte_pair_lanes(le_u32(f, offset));
    fold_lanes(w(0) + w(4) + w(8) + w(12), f[16] as u32 + f[17] as u32)
}

/// Decodes a burst of `model.burst_len()` bytes (after the command word) and checks its checksum; a frame
/// of zero bytes only is [`AdisError::DeadBus`] (its checksum would match).
///
/// Straight-line code on fixed-size arrays: every index is a constant, so there are no bounds checks and
/// no per-channel closure calls on the interrupt path.
#[inline(always)]
pub fn decode_burst<E>(model: Model, bytes: &[u8]) -> Result<Burst, AdisError<E>> {
    if model.burst32() {
        match bytes.first_chunk::<BURST32_LEN>() {
            Some(frame) => decode_burst32(frame),
            None => Err(AdisError::ShortBurst { len: bytes.len() }),
        }
    } else {
        match bytes.first_chunk::<BURST16_LEN>() {
            Some(frame) => decode_burst16(frame),
            None => Err(AdisError::ShortBurst { len: bytes.len() }),
        }
    }
}

/// The largest byte sum of a burst before its checksum word: 30 bytes of 255. It is below 2^16, so the
/// 16-bit sum is exact and is zero only when every byte is zero.
const MAX_BYTE_SUM: usize = (BURST32_LEN - 2) * 255;
const _: () = assert!(MAX_BYTE_SUM < 1 << 16 && BURST16_LEN < BURST32_LEN);

/// The checks shared by both burst formats: the last word must equal the byte sum of the others, and the
/// frame must not be all zero. A data line stuck low delivers zero bytes whose sum, 0, matches the zero
/// checksum word; since the sum is exact ([`MAX_BYTE_SUM`]), a matching zero sum means exactly that every
/// byte of the frame was zero: one comparison with the sum already computed, no second pass over the bytes.
/// (A line stuck high fails the checksum: 30 bytes of 0xFF sum to 0x1DE2, not 0xFFFF.)
#[inline(always)]
fn check_sum<E>(computed: u16, received: u16) -> Result<(), AdisError<E>> {
    if computed != received {
        return Err(AdisError::Checksum { computed, received });
    }
    if computed == 0 {
        return Err(AdisError::DeadBus);
    }
    Ok(())
}

/// One 32-bit channel: the _LOW word, then the _OUT word, each big-endian. Read as one little-endian word
/// `b0 | b1 << 8 | b2 << 16 | b3 << 24`, the value `(b2 b3) << 16 | (b0 b1)` is that word with the bytes of
/// each half swapped (one REV16 on the Cortex-M4).
#[inline(always)]
fn channel32(frame: &[u8; BURST32_LEN], offset: usize) -> I16F16 {
    let x = le_u32(frame, offset);
    I16F16::from_bits((((x & 0x00FF_00FF) << 8) | ((x >> 8) & 0x00FF_00FF)) as i32)
}

/// Decodes the 32-bit burst (ADIS1650x): DIAG_STAT, six channels of two words, TEMP_OUT, DATA_CNTR,
/// checksum.
#[inline(always)]
pub fn decode_burst32<E>(frame: &[u8; BURST32_LEN]) -> Result<Burst, AdisError<E>> {
    check_sum(checksum32(frame), word(frame, 15))?;
    Ok(burst_fields(frame, |i| channel32(frame, 2 + 4 * i), 13))
}

/// Decodes the 16-bit burst (ADIS1647x): DIAG_STAT, six 16-bit channels, TEMP_OUT, DATA_CNTR, checksum.
#[inline(always)]
pub fn decode_burst16<E>(frame: &[u8; BURST16_LEN]) -> Result<Burst, AdisError<E>> {
    check_sum(checksum16(frame), word(frame, 9))?;
    Ok(burst_fields(frame, |i| I16F16::from_bits(((word(frame, 1 + i) as i16) as i32) << 16), 7))
}

/// The fields of either burst format: DIAG_STAT in word 0, the six channels (gyro x, y, z, accel x, y, z)
/// as `channel(i)`, TEMP_OUT in word `temp_word` and DATA_CNTR after it.
#[inline(always)]
fn burst_fields(frame: &[u8], channel: impl Fn(usize) -> I16F16, temp_word: usize) -> Burst {
    Burst {
        diag_stat: word(frame, 0),
        gyro_lsb: [channel(0), channel(1), channel(2)],
        accel_lsb: [channel(3), channel(4), channel(5)],
        temp_raw: word(frame, temp_word) as i16,
        data_counter: word(frame, temp_word + 1),
    }
}

/// Encodes a burst (the inverse of [`decode_burst`], with a valid checksum): what the device would send.
/// Used by the replay device and by tests. A burst whose every field is zero encodes to zero bytes only,
/// which [`decode_burst`] refuses as [`AdisError::DeadBus`]: no sensor at rest delivers it (gravity reads on
/// some axis).
pub fn encode_burst(model: Model, burst: &Burst, out: &mut [u8]) {
    let len = model.burst_len();
    let mut put = |index: usize, value: u16| out[2 * index..2 * index + 2].copy_from_slice(&value.to_be_bytes());
    put(0, burst.diag_stat);
    let (g, a) = (burst.gyro_lsb, burst.accel_lsb);
    let channels = [g[0], g[1], g[2], a[0], a[1], a[2]];
    for (i, v) in channels.iter().enumerate() {
        if model.burst32() {
            let bits = v.to_bits() as u32;
            put(1 + 2 * i, bits as u16);
            put(2 + 2 * i, (bits >> 16) as u16);
        } else {
            put(1 + i, v.to_num::<i16>() as u16);
        }
    }
    let after = if model.burst32() { 13 } else { 7 };
    put(after, burst.temp_raw as u16);
    put(after + 1, burst.data_counter);
    let sum = checksum(&out[..len - 2]);
    out[len - 2..len].copy_from_slice(&sum.to_be_bytes());
}

impl Burst {
    /// The burst in SI units, body frame (the sensor axes are the body axes).
    ///
    /// The fixed-point value is `bits * 2^-16` LSB; it is converted as `(bits as f32) * (scale * 2^-16)`:
    /// one integer-to-float conversion (a single VCVT on the Cortex-M4F) and one multiplication. Scaling by
    /// a power of two is exact, so this equals `to_num::<f32>() * scale` bit for bit (a test shows it),
    /// at a fraction of the cost of the generic conversion.
    #[inline(always)]
    pub fn to_sample(&self, model: Model) -> ImuSample {
        const TWO_POW_MINUS_16: f32 = 1.0 / 65536.0;
        let w = model.radps_per_lsb() * TWO_POW_MINUS_16;
        let a = model.accel_mps2_per_lsb() * TWO_POW_MINUS_16;
        // Written out rather than mapped: size optimisation keeps a three-step loop rolled.
        let (g, f) = (&self.gyro_lsb, &self.accel_lsb);
        ImuSample {
            rate_b_radps: [g[0].to_bits() as f32 * w, g[1].to_bits() as f32 * w, g[2].to_bits() as f32 * w],
            force_b_mps2: [f[0].to_bits() as f32 * a, f[1].to_bits() as f32 * a, f[2].to_bits() as f32 * a],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames whose bytes cover the whole range, so that every lane carries.
    fn frames<const N: usize>() -> impl Iterator<Item = [u8; N]> {
        (0u32..200).map(|seed| core::array::from_fn(|i| (seed.wrapping_mul(2_654_435_761) >> (i % 24)) as u8 ^ i as u8))
    }

    #[test]
    fn written_out_checksums_equal_the_general_one() {
        for f in frames::<BURST32_LEN>().chain([[0xFF; BURST32_LEN], [0; BURST32_LEN]]) {
            let plain = f[..30].iter().map(|&b| b as u32).sum::<u32>() as u16;
            assert_eq!(checksum32(&f), plain);
            assert_eq!(checksum(&f[..30]), plain);
        }
        for f in frames::<BURST16_LEN>().chain([[0xFF; BURST16_LEN]]) {
            let plain = f[..18].iter().map(|&b| b as u32).sum::<u32>() as u16;
            assert_eq!(checksum16(&f), plain);
        }
    }
}
