//! The ADIS1647x/1650x driver against a mock SPI device: the exact transactions of the start-up (software
//! reset, self-test, product check, configuration written and read back, the stall time after every register
//! word, the waits in between) and of burst reads, and every fault the sampling layer must see (bad checksum,
//! an all-zero frame, stalled data counter, flagged status) or the start-up must refuse (failed self-test,
//! wrong product, a register that does not read back, a bus error).
//! Register values are written out here again from the data sheets, independently of the driver.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::delay::{CheckedDelay, Transaction as DelayTransaction};
use embedded_hal_mock::eh1::spi::{Mock, Transaction};
use sinscal::sensor::adis::{decode_burst, encode_burst, Adis, AdisError, Burst, Model, I16F16};
use sinscal::sensor::source::{ClassifiedError, ImuSource, ReadFault};

const BURST_CMD: [u8; 2] = [0x68, 0x00];

// Start-up, written out from the data sheets: GLOB_CMD (0x68) commands as one word to its low byte (0xE880
// software reset, 0xE804 self-test), DIAG_STAT 0x02, PROD_ID 0x72, DEC_RATE 0x64, MSC_CTRL 0x60 (bit 9: 32-bit
// burst, power-on value 0x00C1); every register word followed by the 16 us stall time.
const STALL_NS: u32 = 16_000;
const SOFTWARE_RESET: [u8; 2] = [0xE8, 0x80];
const SELF_TEST: [u8; 2] = [0xE8, 0x04];
const DIAG_STAT: u8 = 0x02;
const PROD_ID: u8 = 0x72;
const DEC_RATE: u8 = 0x64;
const MSC_CTRL: u8 = 0x60;

/// A burst read: the command word and the burst in one chip-select cycle, no stall (burst mode).
fn burst_transaction(response: Vec<u8>) -> Vec<Transaction<u8>> {
    vec![
        Transaction::transaction_start(),
        Transaction::write_vec(BURST_CMD.to_vec()),
        Transaction::read_vec(response),
        Transaction::transaction_end(),
    ]
}

/// A 32-bit burst written out by hand: DIAG, (LOW, OUT) x 6, TEMP, DATA_CNTR, checksum (sum of bytes).
fn burst32(diag: u16, channels_32bit: [i32; 6], temp: i16, counter: u16) -> Vec<u8> {
    let mut words: Vec<u16> = vec![diag];
    for c in channels_32bit {
        words.push(c as u32 as u16);
        words.push(((c as u32) >> 16) as u16);
    }
    words.push(temp as u16);
    words.push(counter);
    let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_be_bytes()).collect();
    let sum = bytes.iter().fold(0u16, |s, &b| s.wrapping_add(b as u16));
    bytes.extend_from_slice(&sum.to_be_bytes());
    assert_eq!(bytes.len(), 32);
    bytes
}

/// One register word in its own chip-select cycle, then the stall.
fn word(bytes: [u8; 2]) -> Vec<Transaction<u8>> {
    vec![
        Transaction::transaction_start(),
        Transaction::write_vec(bytes.to_vec()),
        Transaction::delay(STALL_NS),
        Transaction::transaction_end(),
    ]
}

/// A register read: the address word, then the value in the next word, each followed by the stall.
fn read_reg(address: u8, value: u16) -> Vec<Transaction<u8>> {
    let mut t = word([address, 0x00]);
    t.extend([
        Transaction::transaction_start(),
        Transaction::read_vec(value.to_be_bytes().to_vec()),
        Transaction::delay(STALL_NS),
        Transaction::transaction_end(),
    ]);
    t
}

/// A register write: the low byte to the register's address, the high byte to the next, with the write flag.
fn write_reg(address: u8, value: u16) -> Vec<Transaction<u8>> {
    let mut t = word([0x80 | address, value as u8]);
    t.extend(word([0x80 | (address + 1), (value >> 8) as u8]));
    t
}

/// What happened, in order, on the bus and in the delay: the order of the millisecond waits relative to the
/// commands is what the data sheets prescribe, and neither mock alone can see it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Step {
    Spi,
    FailedSpi,
    DelayNs(u32),
}

type Log = Rc<RefCell<Vec<Step>>>;

/// The SPI mock, logging each transaction; transaction number `fail_at` (0-based) fails as a bus error
/// instead of reaching the mock.
struct LoggedSpi {
    mock: Mock<u8>,
    log: Log,
    fail_at: Option<usize>,
    count: usize,
}

impl ErrorType for LoggedSpi {
    type Error = ErrorKind;
}

impl SpiDevice for LoggedSpi {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        let k = self.count;
        self.count += 1;
        if self.fail_at == Some(k) {
            self.log.borrow_mut().push(Step::FailedSpi);
            return Err(ErrorKind::Other);
        }
        self.log.borrow_mut().push(Step::Spi);
        self.mock.transaction(operations)
    }
}

/// The delay mock (which checks each wait's length), logging into the same log.
struct LoggedDelay {
    mock: CheckedDelay,
    log: Log,
}

impl DelayNs for LoggedDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.log.borrow_mut().push(Step::DelayNs(ns));
        self.mock.delay_ns(ns);
    }
}

/// Runs `init` of `model` against the expected SPI transactions and millisecond waits; returns its result and
/// the log. Both mocks check that everything expected happened, and nothing else.
fn run_init(
    model: Model,
    spi: Vec<Transaction<u8>>,
    waits_ms: &[u32],
    fail_at: Option<usize>,
) -> (Result<(), AdisError<ErrorKind>>, Vec<Step>) {
    let log: Log = Rc::new(RefCell::new(Vec::new()));
    let spi = LoggedSpi { mock: Mock::new(&spi), log: log.clone(), fail_at, count: 0 };
    let waits: Vec<DelayTransaction> = waits_ms.iter().map(|&ms| DelayTransaction::delay_ns(ms * 1_000_000)).collect();
    let mut delay = LoggedDelay { mock: CheckedDelay::new(&waits), log: log.clone() };
    let mut imu = Adis::new(spi, model);
    let result = imu.init(&mut delay);
    imu.release().mock.done();
    delay.mock.done();
    let steps = log.borrow().clone();
    (result, steps)
}

/// The start-up up to and including the self-test's DIAG_STAT read, with DIAG_STAT reading `diag`.
fn reset_and_self_test(diag: u16) -> Vec<Transaction<u8>> {
    let mut t = word(SOFTWARE_RESET);
    t.extend(word(SELF_TEST));
    t.extend(read_reg(DIAG_STAT, diag));
    t
}

/// `n` SPI transactions in the log.
fn spi(n: usize) -> Vec<Step> {
    vec![Step::Spi; n]
}

/// Reset, its 260 ms, self-test, its 30 ms (ADIS1650x), then `n` more SPI transactions.
fn startup_log(n: usize) -> Vec<Step> {
    let mut steps = vec![Step::Spi, Step::DelayNs(260_000_000), Step::Spi, Step::DelayNs(30_000_000)];
    steps.extend(spi(n));
    steps
}

#[test]
fn init_resets_self_tests_checks_the_product_and_reads_the_configuration_back() {
    let mut t = reset_and_self_test(0);
    t.extend(read_reg(PROD_ID, 16505));
    t.extend(write_reg(DEC_RATE, 19));
    t.extend(read_reg(DEC_RATE, 19));
    t.extend(read_reg(MSC_CTRL, 0x00C1));
    // MSC_CTRL |= bit 9 (32-bit burst): 0x02C1, low byte then high byte, then read back.
    t.extend(write_reg(MSC_CTRL, 0x02C1));
    t.extend(read_reg(MSC_CTRL, 0x02C1));
    let (result, steps) = run_init(Model::Adis16505_2, t, &[260, 30], None);
    assert_eq!(result, Ok(()));
    // Reset, wait, self-test, wait, then DIAG_STAT, PROD_ID, DEC_RATE written and read, MSC_CTRL read,
    // written and read: 14 words.
    assert_eq!(steps, startup_log(14));
}

#[test]
fn init_of_the_adis16470_waits_its_own_times_and_keeps_the_16_bit_burst() {
    let mut t = reset_and_self_test(0);
    t.extend(read_reg(PROD_ID, 16470));
    t.extend(write_reg(DEC_RATE, 19));
    t.extend(read_reg(DEC_RATE, 19));
    let (result, steps) = run_init(Model::Adis16470, t, &[200, 20], None);
    assert_eq!(result, Ok(()));
    let mut expected = vec![Step::Spi, Step::DelayNs(200_000_000), Step::Spi, Step::DelayNs(20_000_000)];
    expected.extend(spi(8));
    assert_eq!(steps, expected);
}

#[test]
fn a_failed_self_test_stops_the_start_up_with_the_flags() {
    // DIAG_STAT bit 5 (sensor failure) after the self-test: nothing is read or written after it.
    let (result, steps) = run_init(Model::Adis16505_2, reset_and_self_test(0x0020), &[260, 30], None);
    assert_eq!(result, Err(AdisError::SelfTest { diag_stat: 0x0020 }));
    assert_eq!(result.unwrap_err().fault(), ReadFault::StatusFlag);
    assert_eq!(steps, startup_log(2));
}

#[test]
fn wrong_product_is_refused() {
    let mut t = reset_and_self_test(0);
    t.extend(read_reg(PROD_ID, 16470));
    let (result, steps) = run_init(Model::Adis16505_2, t, &[260, 30], None);
    assert_eq!(result, Err(AdisError::WrongProduct { expected: 16505, found: 16470 }));
    assert_eq!(steps, startup_log(4));
}

#[test]
fn a_configuration_that_does_not_read_back_is_refused() {
    // DEC_RATE reads back its power-on 0: the write did not take.
    let mut t = reset_and_self_test(0);
    t.extend(read_reg(PROD_ID, 16505));
    t.extend(write_reg(DEC_RATE, 19));
    t.extend(read_reg(DEC_RATE, 0));
    let (result, _) = run_init(Model::Adis16505_2, t, &[260, 30], None);
    assert_eq!(result, Err(AdisError::ReadBack { register: DEC_RATE, written: 19, read: 0 }));
    // MSC_CTRL without its 32-bit burst bit: the driver would misread every burst.
    let mut t = reset_and_self_test(0);
    t.extend(read_reg(PROD_ID, 16505));
    t.extend(write_reg(DEC_RATE, 19));
    t.extend(read_reg(DEC_RATE, 19));
    t.extend(read_reg(MSC_CTRL, 0x00C1));
    t.extend(write_reg(MSC_CTRL, 0x02C1));
    t.extend(read_reg(MSC_CTRL, 0x00C1));
    let (result, steps) = run_init(Model::Adis16505_2, t, &[260, 30], None);
    assert_eq!(result, Err(AdisError::ReadBack { register: MSC_CTRL, written: 0x02C1, read: 0x00C1 }));
    assert_eq!(steps, startup_log(14));
}

#[test]
fn a_bus_error_stops_the_start_up_where_it_happens() {
    // The self-test command (the second transaction) fails on the bus: no wait for a self-test that never
    // started, nothing after it.
    let (result, steps) = run_init(Model::Adis16505_2, word(SOFTWARE_RESET), &[260], Some(1));
    assert_eq!(result, Err(AdisError::Spi(ErrorKind::Other)));
    assert_eq!(result.unwrap_err().fault(), ReadFault::Bus);
    assert_eq!(steps, vec![Step::Spi, Step::DelayNs(260_000_000), Step::FailedSpi]);
    // The value word of the PROD_ID read (transaction 5) fails.
    let mut t = reset_and_self_test(0);
    t.extend(word([PROD_ID, 0x00]));
    let (result, steps) = run_init(Model::Adis16505_2, t, &[260, 30], Some(5));
    assert_eq!(result, Err(AdisError::Spi(ErrorKind::Other)));
    let mut expected = startup_log(3);
    expected.push(Step::FailedSpi);
    assert_eq!(steps, expected);
}

#[test]
fn an_all_zero_frame_is_a_dead_bus_not_a_sample() {
    // MISO stuck low: 32 zero bytes, whose byte sum (0) matches the zero checksum word.
    let zeros = vec![0u8; 32];
    assert_eq!(zeros.iter().fold(0u16, |s, &b| s.wrapping_add(b as u16)), 0, "the checksum cannot see it");
    // MISO stuck high: the sum of 30 bytes of 0xFF is 0x1DE2, not 0xFFFF: a checksum error.
    let ones = vec![0xFFu8; 32];
    // A frame with only the data counter non-zero is a valid frame (the check is not on the sample values).
    let counter_only = burst32(0, [0; 6], 0, 1);
    let mut expectations = burst_transaction(zeros.clone());
    expectations.extend(burst_transaction(ones));
    expectations.extend(burst_transaction(counter_only));
    let mut imu = Adis::new(Mock::new(&expectations), Model::Adis16505_2);
    let e = imu.read().unwrap_err();
    assert_eq!(e, AdisError::DeadBus);
    assert_eq!(e.fault(), ReadFault::DeadBus);
    assert_eq!(imu.read().unwrap_err(), AdisError::Checksum { computed: 30 * 255, received: 0xFFFF });
    assert_eq!(imu.read().unwrap().counter, 1);
    imu.release().done();
    // The 16-bit burst of the ADIS16470 too.
    assert_eq!(decode_burst::<()>(Model::Adis16470, &[0u8; 20]), Err(AdisError::DeadBus));
}

#[test]
fn burst_is_decoded_to_si_with_the_datasheet_scales() {
    // ADIS16505-2: 40 LSB per deg/s, 78/32000 m/s^2 per LSB (16-bit); 32-bit values are LSB * 65536.
    // Gyro x = +1.5 deg/s = 60 LSB; gyro y = -0.25 LSB (fraction only); z = 0.
    // Accel z = 1 g = 9.80665 / (78/32000) = 4023.24 LSB (32-bit 263,667,276 rounded).
    let accel_z_32 = (9.80665f64 / (78.0 / 32000.0) * 65536.0).round() as i32;
    let frame = burst32(0, [60 << 16, -(1 << 14), 0, 0, 0, accel_z_32], 250, 7);
    let mut expectations = burst_transaction(frame.clone());
    expectations.extend(burst_transaction(burst32(0, [0; 6], 250, 8)));
    expectations.extend(burst_transaction(burst32(0, [0; 6], 250, 11)));
    let mut imu = Adis::new(Mock::new(&expectations), Model::Adis16505_2);
    let r = imu.read().unwrap();
    let dps = std::f32::consts::PI / 180.0;
    assert!((r.sample.rate_b_radps[0] - 1.5 * dps).abs() < 1e-7);
    assert!((r.sample.rate_b_radps[1] + 0.25 / 40.0 * dps).abs() < 1e-9);
    assert!((r.sample.force_b_mps2[2] - 9.80665).abs() < 1e-5, "{}", r.sample.force_b_mps2[2]);
    assert_eq!((r.counter, r.missed), (7, 0));
    assert!((r.temperature_c - 25.0).abs() < 1e-6);
    // Counter 8 follows 7: nothing missed. Counter 11 follows 8: two samples missed.
    assert_eq!(imu.read().unwrap().missed, 0);
    assert_eq!(imu.read().unwrap().missed, 2);
    imu.release().done();
}

#[test]
fn bad_checksum_stalled_counter_and_flagged_status_are_reported() {
    let mut corrupted = burst32(0, [1 << 16, 0, 0, 0, 0, 4023 << 16], 250, 1);
    corrupted[5] ^= 0x10; // one bit flipped in transit
    let good = burst32(0, [0; 6], 250, 2);
    let flagged = burst32(0x0020, [0; 6], 250, 3); // DIAG_STAT bit 5: sensor failure
    let mut expectations = burst_transaction(corrupted);
    expectations.extend(burst_transaction(good.clone()));
    expectations.extend(burst_transaction(good)); // same counter again
    expectations.extend(burst_transaction(flagged));
    let mut imu = Adis::new(Mock::new(&expectations), Model::Adis16505_2);

    let e = imu.read().unwrap_err();
    assert!(matches!(e, AdisError::Checksum { .. }), "{e:?}");
    assert_eq!(e.fault(), ReadFault::Checksum);
    imu.read().unwrap();
    let e = imu.read().unwrap_err();
    assert_eq!(e, AdisError::StalledCounter { counter: 2 });
    assert_eq!(e.fault(), ReadFault::StalledCounter);
    let e = imu.read().unwrap_err();
    assert_eq!(e, AdisError::Status { diag_stat: 0x0020 });
    assert_eq!(e.fault(), ReadFault::StatusFlag);
    imu.release().done();
}

#[test]
fn sixteen_bit_burst_of_the_adis16470() {
    // DIAG, X/Y/Z_GYRO_OUT, X/Y/Z_ACCL_OUT, TEMP, DATA_CNTR, checksum. 10 LSB per deg/s, 800 LSB per g.
    let words: [u16; 9] = [0, 100, (-20i16) as u16, 0, 0, 0, 800, 300, 42];
    let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_be_bytes()).collect();
    let sum = bytes.iter().fold(0u16, |s, &b| s.wrapping_add(b as u16));
    bytes.extend_from_slice(&sum.to_be_bytes());
    let mut imu = Adis::new(Mock::new(&burst_transaction(bytes)), Model::Adis16470);
    let r = imu.read().unwrap();
    let dps = std::f32::consts::PI / 180.0;
    assert!((r.sample.rate_b_radps[0] - 10.0 * dps).abs() < 1e-6);
    assert!((r.sample.rate_b_radps[1] + 2.0 * dps).abs() < 1e-6);
    assert!((r.sample.force_b_mps2[2] - 9.80665).abs() < 1e-5);
    assert_eq!(r.counter, 42);
    imu.release().done();
}

#[test]
fn encode_and_decode_are_inverse() {
    let burst = Burst {
        diag_stat: 0,
        gyro_lsb: [I16F16::from_bits(123_456), I16F16::from_bits(-7), I16F16::from_bits(i32::MIN)],
        accel_lsb: [I16F16::from_bits(1), I16F16::from_bits(0), I16F16::from_bits(i32::MAX)],
        temp_raw: -12,
        data_counter: 65535,
    };
    let mut bytes = [0u8; 32];
    encode_burst(Model::Adis16505_2, &burst, &mut bytes);
    assert_eq!(decode_burst::<()>(Model::Adis16505_2, &bytes), Ok(burst));
    assert_eq!(decode_burst::<()>(Model::Adis16505_2, &bytes[..20]), Err(AdisError::ShortBurst { len: 20 }));
}

#[test]
fn word_parallel_checksum_equals_the_byte_sum() {
    let mut state = 12345u32;
    for len in [0usize, 1, 2, 3, 4, 18, 30, 31, 32, 64, 255] {
        for _ in 0..50 {
            let bytes: Vec<u8> = (0..len)
                .map(|_| {
                    state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
                    (state >> 16) as u8
                })
                .collect();
            let plain = bytes.iter().fold(0u16, |s, &b| s.wrapping_add(b as u16));
            assert_eq!(sinscal::sensor::adis::checksum(&bytes), plain, "{bytes:?}");
        }
    }
    assert_eq!(sinscal::sensor::adis::checksum(&[0xFF; 30]), 30 * 255);
}

#[test]
fn vcvt_conversion_equals_fixed_to_num_bit_for_bit() {
    // Burst::to_sample converts (bits as f32) * (scale * 2^-16); the generic fixed conversion is
    // to_num::<f32>() * scale. Scaling by a power of two is exact, so both round once, identically.
    let model = Model::Adis16505_2;
    let mut state = 0x9E37_79B9u32;
    for _ in 0..200_000 {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        let v = I16F16::from_bits(state as i32);
        let burst = Burst { diag_stat: 0, gyro_lsb: [v; 3], accel_lsb: [v; 3], temp_raw: 0, data_counter: 0 };
        let s = burst.to_sample(model);
        assert_eq!(s.rate_b_radps[0].to_bits(), (v.to_num::<f32>() * model.radps_per_lsb()).to_bits(), "{v}");
        assert_eq!(s.force_b_mps2[0].to_bits(), (v.to_num::<f32>() * model.accel_mps2_per_lsb()).to_bits(), "{v}");
    }
}
