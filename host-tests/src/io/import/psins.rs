//! The PSINS `.imu` importer: angle and velocity increment counts of one static pose.

use super::*;

/// Reads a PSINS `.imu` file; see [`parse_psins`].
pub fn import_psins(path: &Path, latitude_deg: Option<f64>) -> Result<Imported, InputError> {
    parse_psins(&read_text(path)?, &path.display().to_string(), latitude_deg)
}

/// Parses the text of a PSINS `.imu` file (`source` names it in errors and in the `# source:` header).
///
/// Lines starting with '%' are comments. Data line 1: pitch, roll, yaw (deg; PSINS yaw is positive towards west,
/// so heading = -yaw brought into [0, 360)), VE, VN, VU (m/s, ignored). Line 2: latitude (deg), longitude (deg),
/// height (m), t0 (s), sampling interval (ms), g (m/s^2). Line 3: gyro scale per count (arcsec) x, y, z and
/// accelerometer scale per count (ug*s, 1 ug = 1e-6 * g of line 2) x, y, z. Then one line of six integer
/// increment counts per sample (gyro x, y, z, accel x, y, z), converted as
/// rate_radps = count * scale_arcsec * (pi / 648000) / dt_s and force_mps2 = count * scale_ugs * 1e-6 * g / dt_s.
/// Row k has t_s = t0 + k * dt_s. The record is one static pose: every row has pos = 1 and the attitude of line 1.
/// `latitude_deg` overrides the file's latitude.
pub fn parse_psins(text: &str, source: &str, latitude_deg: Option<f64>) -> Result<Imported, InputError> {
    let latitude_override = option_latitude(latitude_deg, "--latitude-deg")?;
    let last_line = text.lines().count().max(1);
    let mut lines =
        text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty() && !l.starts_with('%'));
    let mut header_line = |what: &str| -> Result<(usize, Vec<f64>), InputError> {
        let (n, line) = lines
            .next()
            .ok_or_else(|| InputError::at(source, last_line, format!("end of file before the {what} line")))?;
        let values = whitespace_numbers(line, 6, what).map_err(|r| InputError::at(source, n, r))?;
        Ok((n, values))
    };
    let attitude = header_line("attitude (pitch roll yaw deg, VE VN VU m/s)")?;
    let site = header_line("site (latitude deg, longitude deg, height m, t0 s, interval ms, g m/s^2)")?;
    let scale = header_line("scale (gyro arcsec x y z, accel ug*s x y z)")?;
    let header = psins_header(attitude, site, scale, source)?;
    let rows = psins_rows(lines, &header, source)?;
    if rows.is_empty() {
        return Err(InputError::at(source, last_line, "no data lines after the three header lines"));
    }
    Ok(psins_imported(&header, rows, source, latitude_override))
}

/// The three PSINS header lines, checked, with the count-to-unit factors they imply.
struct PsinsHeader {
    /// Line number of the attitude line.
    attitude_line: usize,
    /// Pitch, deg.
    pitch_deg: f64,
    /// Roll, deg.
    roll_deg: f64,
    /// PSINS yaw, deg, positive towards west.
    yaw_deg: f64,
    /// Heading = -yaw in [0, 360), deg.
    heading_deg: f64,
    /// Line number of the site line.
    site_line: usize,
    /// Latitude of the site line, deg.
    file_latitude_deg: f64,
    /// Longitude, deg.
    longitude_deg: f64,
    /// Height, m.
    height_m: f64,
    /// Time of the first sample, s.
    t0_s: f64,
    /// Sampling interval, s.
    dt_s: f64,
    /// Sampling rate, Hz.
    rate_hz: f64,
    /// Gravity of the site line, m/s^2.
    gravity_mps2: f64,
    /// The six scale factors of the scale line (gyro arcsec, accel ug*s per count).
    scale: Vec<f64>,
    /// Gyro rate per count, rad/s.
    gyro_radps_per_count: [f64; 3],
    /// Accelerometer force per count, m/s^2.
    accel_mps2_per_count: [f64; 3],
}

/// Checks the attitude, site and scale header lines (each with its line number) and derives the conversion factors.
fn psins_header(
    (attitude_line, attitude): (usize, Vec<f64>),
    (site_line, site): (usize, Vec<f64>),
    (scale_line, scale): (usize, Vec<f64>),
    source: &str,
) -> Result<PsinsHeader, InputError> {
    let (pitch_deg, roll_deg, yaw_deg) = (attitude[0], attitude[1], attitude[2]);
    if !(-90.0..=90.0).contains(&pitch_deg) {
        return Err(InputError::at(source, attitude_line, format!("pitch {pitch_deg} deg is outside [-90, 90]")));
    }
    let heading_deg = normalise_deg(-yaw_deg);
    let file_latitude_deg = latitude_checked(site[0], source, site_line)?;
    let (longitude_deg, height_m, t0_s, interval_ms, gravity_mps2) = (site[1], site[2], site[3], site[4], site[5]);
    if interval_ms <= 0.0 {
        return Err(InputError::at(source, site_line, format!("sampling interval {interval_ms} ms is not positive")));
    }
    if !crate::io::recording::gravity_ok(gravity_mps2) {
        return Err(InputError::at(
            source,
            site_line,
            format!("g {gravity_mps2} m/s^2 is not a gravity on Earth (9.7..9.9)"),
        ));
    }
    if let Some(bad) = scale.iter().find(|s| **s <= 0.0) {
        return Err(InputError::at(source, scale_line, format!("scale {bad} per count is not positive")));
    }
    let dt_s = interval_ms / 1000.0;
    let rate_hz = 1000.0 / interval_ms;
    let gyro_radps_per_count = [0, 1, 2].map(|i| scale[i] / ARCSEC_PER_RAD / dt_s);
    let accel_mps2_per_count = [3, 4, 5].map(|i| scale[i] * 1e-6 * gravity_mps2 / dt_s);
    // A subnormal interval or a huge scale overflows the rate and the factors per count to infinity.
    if !rate_hz.is_finite() || !gyro_radps_per_count.iter().chain(&accel_mps2_per_count).all(|f| f.is_finite()) {
        let shown = crate::io::recording::shown;
        return Err(InputError::at(
            source,
            site_line,
            format!(
                "sampling interval {} ms: the rate or a scale per second is not a finite number",
                shown(interval_ms)
            ),
        ));
    }
    Ok(PsinsHeader {
        attitude_line,
        pitch_deg,
        roll_deg,
        yaw_deg,
        heading_deg,
        site_line,
        file_latitude_deg,
        longitude_deg,
        height_m,
        t0_s,
        dt_s,
        rate_hz,
        gravity_mps2,
        scale,
        gyro_radps_per_count,
        accel_mps2_per_count,
    })
}

/// Converts the data lines (six integer counts each) into rows of the one static pose.
fn psins_rows<'a>(
    lines: impl Iterator<Item = (usize, &'a str)>,
    h: &PsinsHeader,
    source: &str,
) -> Result<Vec<Row>, InputError> {
    let mut rows = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split_whitespace().collect();
        if cells.len() != 6 {
            return Err(InputError::at(
                source,
                n,
                format!("expected 6 integer counts (gyro x y z, accel x y z), found {} fields", cells.len()),
            ));
        }
        let mut counts = [0i64; 6];
        for (slot, cell) in counts.iter_mut().zip(&cells) {
            *slot = cell.parse().map_err(|_| InputError::at(source, n, format!("'{cell}' is not an integer count")))?;
        }
        let k = rows.len() as f64;
        let t_s = h.t0_s + k * h.dt_s;
        let rate_b_radps = [0, 1, 2].map(|i| counts[i] as f64 * h.gyro_radps_per_count[i]);
        let force_b_mps2 = [0, 1, 2].map(|i| counts[i + 3] as f64 * h.accel_mps2_per_count[i]);
        if !rate_b_radps.iter().chain(&force_b_mps2).chain([&t_s]).all(|v| v.is_finite()) {
            return Err(InputError::at(source, n, "a count times its scale, or the time, is not a finite number"));
        }
        rows.push(Row {
            t_s,
            pos: 1,
            pitch_deg: h.pitch_deg,
            roll_deg: h.roll_deg,
            heading_deg: Some(h.heading_deg),
            rate_b_radps,
            force_b_mps2,
            temp_c: None,
            turn_axis: None,
            line: n,
        });
    }
    Ok(rows)
}

/// Assembles the recording (header comments included) and its import summary from the checked header and rows.
fn psins_imported(h: &PsinsHeader, rows: Vec<Row>, source: &str, latitude_override: Option<f64>) -> Imported {
    let PsinsHeader {
        attitude_line,
        pitch_deg,
        roll_deg,
        yaw_deg,
        heading_deg,
        site_line,
        file_latitude_deg,
        longitude_deg,
        height_m,
        dt_s,
        rate_hz,
        gravity_mps2,
        ref scale,
        ..
    } = *h;
    let (latitude_deg, latitude_source) = match latitude_override {
        Some(lat) => (lat, format!("command line (--latitude-deg; the file says {file_latitude_deg})")),
        None => (file_latitude_deg, format!("file header (line {site_line})")),
    };
    let comments = vec![
        format!("source: {source}"),
        "source_format: PSINS .imu (gyro angle increments in arcsec and accel velocity increments in ug*s, counts)"
            .to_string(),
        format!("latitude_source: {latitude_source}"),
        format!("longitude_deg: {longitude_deg}"),
        format!(
            "attitude_source: file header line {attitude_line} (PSINS pitch {pitch_deg}, roll {roll_deg}, \
             yaw {yaw_deg} deg positive west; heading = -yaw = {heading_deg} deg)"
        ),
        format!(
            "scale: gyro {} {} {} arcsec/count, accel {} {} {} ug*s/count, g {gravity_mps2} m/s^2, dt {dt_s} s",
            scale[0], scale[1], scale[2], scale[3], scale[4], scale[5]
        ),
    ];
    let recording = Recording {
        source: source.to_string(),
        header: Header {
            latitude_deg,
            height_m,
            rate_hz: Some(rate_hz),
            gravity_mps2: Some(gravity_mps2),
            comments,
            truth: None,
            pose_tolerance_deg: None,
        },
        rows,
        has_gyro: true,
    };
    let notes = vec![
        format!("latitude {latitude_deg} deg ({latitude_source}), height {height_m} m, g {gravity_mps2} m/s^2"),
        format!("one static pose: pitch {pitch_deg}, roll {roll_deg}, heading {heading_deg} deg (PSINS yaw {yaw_deg})"),
    ];
    let summary = summarise(&recording, "PSINS .imu", &notes, &|_| String::new());
    Imported { recording, summary }
}
