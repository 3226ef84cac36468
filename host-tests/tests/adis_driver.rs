//! The ADIS1647x/1650x driver against a mock SPI device: the exact transactions, and every fault the
//! sampling layer must see (bad checksum, stalled data counter, flagged status, wrong product).
//! Register values are written out here again from the data sheets, independently of the driver.

use embedded_hal_mock::eh1::spi::{Mock, Transaction};
use sinscal::sensor::adis::{decode_burst, encode_burst, Adis, AdisError, Burst, Model, I16F16};
use sinscal::sensor::source::{ClassifiedError, ImuSource, ReadFault};

const PROD_ID_READ: [u8; 2] = [0x72, 0x00];
const DEC_RATE_WRITE_LOW: [u8; 2] = [0x80 | 0x64, 19];
const DEC_RATE_WRITE_HIGH: [u8; 2] = [0x80 | 0x65, 0];
const MSC_CTRL_READ: [u8; 2] = [0x60, 0x00];
const BURST_CMD: [u8; 2] = [0x68, 0x00];

fn single_write(bytes: &[u8]) -> Vec<Transaction<u8>> {
    vec![Transaction::transaction_start(), Transaction::write_vec(bytes.to_vec()), Transaction::transaction_end()]
}

fn single_read(bytes: &[u8]) -> Vec<Transaction<u8>> {
    vec![Transaction::transaction_start(), Transaction::read_vec(bytes.to_vec()), Transaction::transaction_end()]
}

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

#[test]
fn init_checks_the_product_and_sets_100_hz_and_the_32_bit_burst() {
    let mut expectations = Vec::new();
    expectations.extend(single_write(&PROD_ID_READ));
    expectations.extend(single_read(&16505u16.to_be_bytes()));
    expectations.extend(single_write(&DEC_RATE_WRITE_LOW));
    expectations.extend(single_write(&DEC_RATE_WRITE_HIGH));
    expectations.extend(single_write(&MSC_CTRL_READ));
    expectations.extend(single_read(&0x00C1u16.to_be_bytes()));
    // MSC_CTRL |= bit 9 (BURST_SEL): 0x02C1, low byte then high byte.
    expectations.extend(single_write(&[0x80 | 0x60, 0xC1]));
    expectations.extend(single_write(&[0x80 | 0x61, 0x02]));
    let spi = Mock::new(&expectations);
    let mut imu = Adis::new(spi, Model::Adis16505_2);
    imu.init().unwrap();
    imu.release().done();
}

#[test]
fn wrong_product_is_refused() {
    let mut expectations = single_write(&PROD_ID_READ);
    expectations.extend(single_read(&16470u16.to_be_bytes()));
    let mut imu = Adis::new(Mock::new(&expectations), Model::Adis16505_2);
    assert_eq!(imu.init(), Err(AdisError::WrongProduct { expected: 16505, found: 16470 }));
    imu.release().done();
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
