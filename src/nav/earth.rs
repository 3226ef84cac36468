//! Earth model: rotation rate, WGS-84 normal gravity, and the navigation-frame reference vectors of a
//! body at rest (docs/conventions.md: ENU navigation frame).

use crate::math::linalg::Vec3;

/// Earth rotation rate relative to inertial space, rad/s (WGS-84, docs/conventions.md).
pub const EARTH_RATE_RADPS: f32 = 7.292115e-5;

/// Standard gravity, m/s^2: the unit behind "g" and "ug" in human-facing text (1 ug = 9.80665e-6 m/s^2).
pub const STANDARD_GRAVITY_MPS2: f32 = 9.80665;

/// WGS-84 semi-major axis, m (NIMA TR8350.2, table 3.1).
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS-84 flattening (TR8350.2, table 3.1).
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS-84 normal gravity at the equator, m/s^2 (TR8350.2, table 3.4).
pub const WGS84_GAMMA_E_MPS2: f64 = 9.780_325_335_9;
/// WGS-84 Somigliana constant k (TR8350.2, table 3.4).
pub const WGS84_SOMIGLIANA_K: f64 = 0.001_931_852_652_41;
/// WGS-84 first eccentricity squared (TR8350.2, table 3.3).
pub const WGS84_E2: f64 = 0.006_694_379_990_14;
/// WGS-84 m = omega^2 a^2 b / GM (TR8350.2, table 3.3).
pub const WGS84_M: f64 = 0.003_449_786_003_08;

/// Normal gravity at geodetic latitude `latitude_rad` and height `height_m` above the ellipsoid, m/s^2.
///
/// Somigliana's closed formula on the ellipsoid (TR8350.2 eq. 4-1)
///     gamma = gamma_e (1 + k sin^2 L) / sqrt(1 - e^2 sin^2 L)
/// with the second-order free-air correction (TR8350.2 eq. 4-3)
///     gamma_h = gamma [1 - 2/a (1 + f + m - 2 f sin^2 L) h + 3 h^2 / a^2].
/// Evaluated in f32 (no soft-float f64 on the target): every term is of order one or a small correction,
/// so the result is within a few f32 ulp (about 2e-6 m/s^2, 0.2 ug) of the f64 evaluation (a test shows it).
pub fn normal_gravity_mps2(latitude_rad: f32, height_m: f32) -> f32 {
    let s = libm::sinf(latitude_rad);
    let s2 = s * s;
    let (gamma_e, k, e2) = (WGS84_GAMMA_E_MPS2 as f32, WGS84_SOMIGLIANA_K as f32, WGS84_E2 as f32);
    let (a, f, m) = (WGS84_A_M as f32, WGS84_F as f32, WGS84_M as f32);
    let gamma = gamma_e * (1.0 + k * s2) / libm::sqrtf(1.0 - e2 * s2);
    let h = height_m;
    let corr = 1.0 - 2.0 / a * (1.0 + f + m - 2.0 * f * s2) * h + 3.0 * h * h / (a * a);
    gamma * corr
}

/// Where the calibration happens: latitude and the magnitude of gravity used by the alignment.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Site {
    /// Geodetic latitude, rad (north positive).
    pub latitude_rad: f32,
    /// Magnitude of gravity (the specific force of a body at rest), m/s^2.
    pub gravity_mps2: f32,
}

impl Site {
    /// A site with normal gravity at the given latitude and height.
    pub fn with_normal_gravity(latitude_rad: f32, height_m: f32) -> Site {
        Site { latitude_rad, gravity_mps2: normal_gravity_mps2(latitude_rad, height_m) }
    }

    /// Specific force of a body at rest in the navigation frame: `f_n = [0, 0, +g]` (ENU, pointing up).
    pub fn force_at_rest_n_mps2(&self) -> Vec3 {
        [0.0, 0.0, self.gravity_mps2]
    }

    /// Earth rotation in the navigation frame: `w_ie_n = [0, W cos L, W sin L]` (ENU).
    pub fn earth_rate_n_radps(&self) -> Vec3 {
        [0.0, EARTH_RATE_RADPS * libm::cosf(self.latitude_rad), EARTH_RATE_RADPS * libm::sinf(self.latitude_rad)]
    }

    /// Horizontal (north) component of Earth rotation `Omega_n = W cos L`, rad/s.
    pub fn earth_rate_north_radps(&self) -> f32 {
        EARTH_RATE_RADPS * libm::cosf(self.latitude_rad)
    }

    /// `tan L` (dimensionless), as sin L / cos L (one less maths routine on the target).
    pub fn tan_latitude(&self) -> f32 {
        libm::sinf(self.latitude_rad) / libm::cosf(self.latitude_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_gravity_matches_published_values() {
        // TR8350.2 table 3.4: gamma_e = 9.7803253359 at the equator, gamma_p = 9.8321849378 at the poles.
        assert!((normal_gravity_mps2(0.0, 0.0) as f64 - 9.780_325_335_9).abs() < 2e-6);
        let pole = normal_gravity_mps2(core::f32::consts::FRAC_PI_2, 0.0);
        assert!((pole as f64 - 9.832_184_937_8).abs() < 2e-6, "{pole}");
        // Free-air gradient near the surface is about -3.086e-6 (m/s^2)/m.
        let lat = 45.0f32.to_radians();
        let dg = normal_gravity_mps2(lat, 1000.0) - normal_gravity_mps2(lat, 0.0);
        assert!((dg + 3.086e-3).abs() < 1e-5, "{dg}");
    }

    #[test]
    fn f32_normal_gravity_matches_an_f64_evaluation() {
        for lat_deg in [-80.0f64, -30.0, 0.0, 12.5, 45.7796, 89.0] {
            for h in [0.0f64, 380.0, 4000.0] {
                let s2 = lat_deg.to_radians().sin().powi(2);
                let g = WGS84_GAMMA_E_MPS2 * (1.0 + WGS84_SOMIGLIANA_K * s2) / (1.0 - WGS84_E2 * s2).sqrt();
                let g = g
                    * (1.0 - 2.0 / WGS84_A_M * (1.0 + WGS84_F + WGS84_M - 2.0 * WGS84_F * s2) * h
                        + 3.0 * h * h / (WGS84_A_M * WGS84_A_M));
                let got = normal_gravity_mps2((lat_deg as f32).to_radians(), h as f32) as f64;
                assert!((got - g).abs() < 3e-6, "{lat_deg} {h}: {got} vs {g}");
            }
        }
    }

    #[test]
    fn earth_rate_is_north_and_up_in_enu() {
        let site = Site::with_normal_gravity(30.0f32.to_radians(), 0.0);
        let w = site.earth_rate_n_radps();
        assert_eq!(w[0], 0.0);
        assert!((w[1] - EARTH_RATE_RADPS * 0.866_025_4).abs() < 1e-11);
        assert!((w[2] - EARTH_RATE_RADPS * 0.5).abs() < 1e-11);
    }
}
