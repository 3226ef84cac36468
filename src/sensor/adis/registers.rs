//! ADIS1647x/1650x register addresses, constants and models (data sheets, Rev. C / Rev. A).

pub use fixed::types::I16F16;

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
/// MSC_CTRL after power-on or reset (data sheets): linear-g compensation of the gyros (bit 7), point of
/// percussion alignment (bit 6), data-ready active high (bit 0).
pub const MSC_CTRL_DEFAULT: u16 = 0x00C1;
/// GLOB_CMD bit 7: software reset. A command takes effect on the write of GLOB_CMD's low byte.
pub const GLOB_CMD_SOFTWARE_RESET: u8 = 1 << 7;
/// GLOB_CMD bit 2: sensor self-test; its result is in DIAG_STAT bit 5 (sensor failure).
pub const GLOB_CMD_SELF_TEST: u8 = 1 << 2;
/// The stall time between two 16-bit register words outside burst mode, ns (data sheets: t_STALL >= 16 us;
/// the Linux IIO driver waits 16 us between the words of a register access).
pub const STALL_NS: u32 = 16_000;
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

    /// Time from a software reset until the device answers, ms. The ADIS1650x data sheet gives 255 ms for
    /// the recovery from a software reset; the waits here are the Linux IIO driver's `adis16475.c`
    /// (`sw_reset_ms`: 260 ms for ADIS1650x, 200 ms for ADIS1647x), a margin above the data sheets.
    pub const fn reset_recovery_ms(self) -> u32 {
        match self {
            Model::Adis16470 => 200,
            Model::Adis16505_2 => 260,
        }
    }

    /// Time from the self-test command until DIAG_STAT holds its result, ms (the Linux IIO driver's
    /// `self_test_ms`: 30 ms for ADIS1650x, 20 ms for ADIS1647x).
    pub const fn self_test_ms(self) -> u32 {
        match self {
            Model::Adis16470 => 20,
            Model::Adis16505_2 => 30,
        }
    }
}
