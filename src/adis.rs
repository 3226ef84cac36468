//! Driver for the Analog Devices ADIS1647x / ADIS1650x IMU family over SPI (embedded-hal 1.0).
//!
//! Register map, burst format, checksum and scale factors: ADIS16470 and ADIS16505 data sheets (Analog
//! Devices, Rev. C / Rev. A), as implemented in the Linux IIO driver `drivers/iio/imu/adis16475.c`:
//! - registers are 16-bit, big-endian on the wire; reading register `r` sends the word `[r, 0x00]` and
//!   returns the value in the next word; writing sends `[0x80 | r, low byte]`, `[0x80 | (r+1), high byte]`;
//! - a burst read sends the word `[GLOB_CMD, 0x00]` = 0x6800 and then clocks out the burst:
//!   16-bit burst (ADIS1647x, and ADIS1650x with BURST_SEL = 0): DIAG_STAT, X/Y/Z_GYRO_OUT,
//!   X/Y/Z_ACCL_OUT, TEMP_OUT, DATA_CNTR, checksum (10 words);
//!   32-bit burst (ADIS1650x with MSC_CTRL bit 9 set): DIAG_STAT, then for each of the six channels its
//!   _LOW and _OUT words, TEMP_OUT, DATA_CNTR, checksum (16 words);
//! - the checksum is the 16-bit sum of all preceding bytes of the burst (not the command);
//! - the internal sample rate is 2000 SPS; DEC_RATE = 19 decimates to the 100 Hz output rate;
//! - bursts are read at an SPI clock of at most 1 MHz.
//!
//! The 32-bit outputs are fixed-point values in units of the 16-bit LSB: `OUT` is the integer part and
//! `LOW` the fraction (`I16F16`).

use embedded_hal::spi::{Operation, SpiDevice};
pub use fixed::types::I16F16;

use crate::dwell::ImuSample;
use crate::imu::{ClassifiedError, ImuReading, ImuSource, ReadFault};

/// Register addresses (byte address of the register's low byte).
pub mod reg {
    /// Diagnostic status flags.
    pub const DIAG_STAT: u8 = 0x02;
    /// Sample counter.
    pub const DATA_CNTR: u8 = 0x22;
    /// Miscellaneous control (bit 9: 32-bit burst on ADIS1650x).
    pub const MSC_CTRL: u8 = 0x60;
    /// Decimation: output rate = 2000 SPS / (DEC_RATE + 1).
    pub const DEC_RATE: u8 = 0x64;
    /// Global commands; its read address starts a burst.
    pub const GLOB_CMD: u8 = 0x68;
    /// Product identification (decimal model number, e.g. 16505).
    pub const PROD_ID: u8 = 0x72;
}

/// MSC_CTRL bit selecting the 32-bit burst (ADIS1650x).
pub const MSC_CTRL_BURST32: u16 = 1 << 9;
/// Write flag of the first byte of a register write.
pub const WRITE_FLAG: u8 = 0x80;
/// The burst command word.
pub const BURST_COMMAND: [u8; 2] = [reg::GLOB_CMD, 0x00];
/// Internal sample rate, samples per second.
pub const INTERNAL_RATE_SPS: u16 = 2000;
/// Output rate used by sinscal, Hz.
pub const OUTPUT_RATE_HZ: u16 = 100;
/// DEC_RATE for the output rate: 2000 / (19 + 1) = 100 Hz.
pub const DEC_RATE_FOR_100HZ: u16 = INTERNAL_RATE_SPS / OUTPUT_RATE_HZ - 1;
/// Largest SPI clock for burst reads, Hz.
pub const BURST_MAX_SPI_HZ: u32 = 1_000_000;
/// Bytes of a 16-bit burst after the command word.
pub const BURST16_LEN: usize = 20;
/// Bytes of a 32-bit burst after the command word.
pub const BURST32_LEN: usize = 32;
/// Temperature scale: 0.1 deg C per LSB (data sheets, TEMP_OUT).
pub const TEMP_C_PER_LSB: f32 = 0.1;
/// Radians per degree.
const RAD_PER_DEG: f32 = core::f32::consts::PI / 180.0;

/// Supported models and their scale factors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// ADIS16470: +-2000 deg/s, +-40 g; 16-bit burst.
    Adis16470,
    /// ADIS16505-2: +-500 deg/s, +-8 g; 32-bit burst.
    Adis16505_2,
}

impl Model {
    /// PROD_ID value.
    pub const fn product_id(self) -> u16 {
        match self {
            Model::Adis16470 => 16470,
            Model::Adis16505_2 => 16505,
        }
    }

    /// Gyro sensitivity of the 16-bit output, LSB per deg/s (ADIS16470: 10; ADIS16505-2: 40).
    pub const fn gyro_lsb_per_dps(self) -> f32 {
        match self {
            Model::Adis16470 => 10.0,
            Model::Adis16505_2 => 40.0,
        }
    }

    /// Accelerometer scale of the 16-bit output, m/s^2 per LSB (ADIS16470: 1/800 g with
    /// g = 9.80665; ADIS16505-2: 78/32000 m/s^2, as the Linux driver states it).
    pub const fn accel_mps2_per_lsb(self) -> f32 {
        match self {
            Model::Adis16470 => 9.80665 / 800.0,
            Model::Adis16505_2 => 78.0 / 32000.0,
        }
    }

    /// Whether the driver uses the 32-bit burst.
    pub const fn burst32(self) -> bool {
        matches!(self, Model::Adis16505_2)
    }

    /// Burst length after the command word, bytes.
    pub const fn burst_len(self) -> usize {
        if self.burst32() {
            BURST32_LEN
        } else {
            BURST16_LEN
        }
    }

    /// rad/s per 16-bit LSB.
    pub fn radps_per_lsb(self) -> f32 {
        RAD_PER_DEG / self.gyro_lsb_per_dps()
    }
}

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

/// Errors of the driver. `E` is the SPI device's error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AdisError<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// Checksum mismatch.
    Checksum {
        /// Sum of the received bytes.
        computed: u16,
        /// Checksum word received.
        received: u16,
    },
    /// DATA_CNTR did not advance since the last burst.
    StalledCounter {
        /// The counter value read twice.
        counter: u16,
    },
    /// DIAG_STAT reported a fault.
    Status {
        /// The DIAG_STAT word.
        diag_stat: u16,
    },
    /// The buffer is shorter than the model's burst.
    ShortBurst {
        /// Bytes given.
        len: usize,
    },
    /// PROD_ID is not the configured model's.
    WrongProduct {
        /// Expected PROD_ID.
        expected: u16,
        /// PROD_ID read.
        found: u16,
    },
}

impl<E: core::fmt::Debug> core::fmt::Display for AdisError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            AdisError::Spi(e) => write!(f, "SPI error: {e:?}"),
            AdisError::Checksum { computed, received } => {
                write!(f, "burst checksum {received:#06x} does not match the data ({computed:#06x})")
            }
            AdisError::StalledCounter { counter } => write!(f, "data counter stalled at {counter}"),
            AdisError::Status { diag_stat } => write!(f, "DIAG_STAT flags {diag_stat:#06x}"),
            AdisError::WrongProduct { expected, found } => write!(f, "PROD_ID {found}, expected {expected}"),
            AdisError::ShortBurst { len } => write!(f, "burst of {len} bytes is too short"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for AdisError<E> {}

impl<E: core::fmt::Debug> ClassifiedError for AdisError<E> {
    fn fault(&self) -> ReadFault {
        match self {
            AdisError::Spi(_) | AdisError::WrongProduct { .. } | AdisError::ShortBurst { .. } => ReadFault::Bus,
            AdisError::Checksum { .. } => ReadFault::Checksum,
            AdisError::StalledCounter { .. } => ReadFault::StalledCounter,
            AdisError::Status { .. } => ReadFault::StatusFlag,
        }
    }
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

/// Decodes a burst of `model.burst_len()` bytes (after the command word) and checks its checksum.
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

/// The checksum check shared by both burst formats: the last word must equal the byte sum of the others.
#[inline(always)]
fn check_sum<E>(computed: u16, received: u16) -> Result<(), AdisError<E>> {
    if computed != received {
        return Err(AdisError::Checksum { computed, received });
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
/// Used by the replay device and by tests.
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

/// The driver.
#[derive(Debug)]
pub struct Adis<SPI> {
    spi: SPI,
    model: Model,
    last_counter: Option<u16>,
}

impl<SPI: SpiDevice> Adis<SPI> {
    /// A driver for a device of the given model (no bus traffic yet).
    pub fn new(spi: SPI, model: Model) -> Adis<SPI> {
        Adis { spi, model, last_counter: None }
    }

    /// The model.
    pub fn model(&self) -> Model {
        self.model
    }

    /// The SPI device (for a replay device that is fed frame by frame).
    pub fn spi_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// Reads a 16-bit register: the address word, then the value in the following word.
    pub fn read_register(&mut self, register: u8) -> Result<u16, AdisError<SPI::Error>> {
        self.spi.write(&[register, 0x00]).map_err(AdisError::Spi)?;
        let mut value = [0u8; 2];
        self.spi.read(&mut value).map_err(AdisError::Spi)?;
        Ok(u16::from_be_bytes(value))
    }

    /// Writes a 16-bit register, low byte first.
    pub fn write_register(&mut self, register: u8, value: u16) -> Result<(), AdisError<SPI::Error>> {
        let [high, low] = value.to_be_bytes();
        self.spi.write(&[WRITE_FLAG | register, low]).map_err(AdisError::Spi)?;
        self.spi.write(&[WRITE_FLAG | (register + 1), high]).map_err(AdisError::Spi)
    }

    /// Checks PROD_ID, sets DEC_RATE for 100 Hz and, for ADIS1650x, the 32-bit burst.
    pub fn init(&mut self) -> Result<(), AdisError<SPI::Error>> {
        let found = self.read_register(reg::PROD_ID)?;
        let expected = self.model.product_id();
        if found != expected {
            return Err(AdisError::WrongProduct { expected, found });
        }
        self.write_register(reg::DEC_RATE, DEC_RATE_FOR_100HZ)?;
        if self.model.burst32() {
            let msc = self.read_register(reg::MSC_CTRL)?;
            self.write_register(reg::MSC_CTRL, msc | MSC_CTRL_BURST32)?;
        }
        self.last_counter = None;
        Ok(())
    }

    /// The burst transaction: the command word, then the model's burst into `buf`, in one chip-select
    /// cycle. Returns the bytes received.
    #[inline(always)]
    fn transfer<'b>(&mut self, buf: &'b mut [u8; BURST32_LEN]) -> Result<&'b [u8], AdisError<SPI::Error>> {
        let len = self.model.burst_len();
        self.spi
            .transaction(&mut [Operation::Write(&BURST_COMMAND), Operation::Read(&mut buf[..len])])
            .map_err(AdisError::Spi)?;
        Ok(&buf[..len])
    }

    /// One burst read, decoded but without the counter and status checks.
    #[inline(always)]
    pub fn read_burst(&mut self) -> Result<Burst, AdisError<SPI::Error>> {
        let mut buf = [0u8; BURST32_LEN];
        let bytes = self.transfer(&mut buf)?;
        decode_burst(self.model, bytes)
    }

    /// Everything after the bus transfer: checksum, decode, counter and status checks, conversion to SI.
    /// [`ImuSource::read`] is one burst transaction followed by this; with a DMA transfer, call it on the
    /// received bytes.
    #[inline(always)]
    pub fn decode_reading(&mut self, burst_bytes: &[u8]) -> Result<ImuReading, AdisError<SPI::Error>> {
        let burst = decode_burst(self.model, burst_bytes)?;
        let missed = match self.last_counter {
            Some(last) if burst.data_counter == last => {
                return Err(AdisError::StalledCounter { counter: last });
            }
            Some(last) => burst.data_counter.wrapping_sub(last).wrapping_sub(1),
            None => 0,
        };
        self.last_counter = Some(burst.data_counter);
        if burst.diag_stat != 0 {
            return Err(AdisError::Status { diag_stat: burst.diag_stat });
        }
        Ok(ImuReading {
            sample: burst.to_sample(self.model),
            counter: burst.data_counter,
            missed,
            temperature_c: burst.temp_raw as f32 * TEMP_C_PER_LSB,
        })
    }
}

impl<SPI: SpiDevice> ImuSource for Adis<SPI> {
    type Error = AdisError<SPI::Error>;

    /// Burst read, then [`Adis::decode_reading`].
    fn read(&mut self) -> Result<ImuReading, Self::Error> {
        let mut buf = [0u8; BURST32_LEN];
        let bytes = self.transfer(&mut buf)?;
        self.decode_reading(bytes)
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
