//! Why the core uses libm and not micromath for its f32 maths: a measurement.
//!
//! The alignment resolves angles to about 1e-7 rad (the f32 resolution of a unit vector, the solver's
//! angle floor), and the calibration's accelerometer result needs about 3e-7 rad (3 ug / g). The maths
//! behind it (sqrt of the normal gravity formula and the dwell variances, sin/cos/tan of latitude and
//! turntable angles) must be at least that accurate. This test measures the largest error of both
//! libraries against f64 over the arguments the core uses and prints it; it fails if libm were not good
//! enough, and if micromath ever became good enough (then the choice should be revisited).

use micromath::F32Ext;

struct Worst {
    libm: f64,
    micromath: f64,
}

fn measure(
    args: impl Iterator<Item = f32>,
    exact: impl Fn(f64) -> f64,
    libm_f: impl Fn(f32) -> f32,
    micro_f: impl Fn(f32) -> f32,
    relative: bool,
) -> Worst {
    let mut w = Worst { libm: 0.0, micromath: 0.0 };
    for x in args {
        let e = exact(x as f64);
        let scale = if relative { e.abs().max(1e-300) } else { 1.0 };
        w.libm = w.libm.max((libm_f(x) as f64 - e).abs() / scale);
        w.micromath = w.micromath.max((micro_f(x) as f64 - e).abs() / scale);
    }
    w
}

#[test]
fn libm_is_accurate_enough_for_alignment_and_micromath_is_not() {
    const N: usize = 200_000;
    // Angles of turntable positions and latitudes: -2 pi .. 2 pi.
    let tau = std::f32::consts::TAU;
    let angles = || (0..N).map(|i| -tau + 2.0 * tau * i as f32 / N as f32);
    // Square roots of variances and squared norms: 1e-16 .. 1e3, log-spaced.
    let squares = || (0..N).map(|i| 10f32.powf(-16.0 + 19.0 * i as f32 / N as f32));
    // tan of latitudes up to 80 deg.
    let latitudes = || (0..N).map(|i| -1.396 + 2.792 * i as f32 / N as f32);

    let sin = measure(angles(), f64::sin, libm::sinf, F32Ext::sin, false);
    let cos = measure(angles(), f64::cos, libm::cosf, F32Ext::cos, false);
    let tan = measure(latitudes(), f64::tan, libm::tanf, F32Ext::tan, true);
    let sqrt = measure(squares(), f64::sqrt, libm::sqrtf, F32Ext::sqrt, true);
    println!("largest error against f64 ({N} arguments each):");
    println!("  sin  (abs): libm {:.1e}  micromath {:.1e}", sin.libm, sin.micromath);
    println!("  cos  (abs): libm {:.1e}  micromath {:.1e}", cos.libm, cos.micromath);
    println!("  tan  (rel): libm {:.1e}  micromath {:.1e}", tan.libm, tan.micromath);
    println!("  sqrt (rel): libm {:.1e}  micromath {:.1e}", sqrt.libm, sqrt.micromath);

    const NEEDED: f64 = 1e-7;
    for (name, w) in [("sin", &sin), ("cos", &cos), ("tan", &tan), ("sqrt", &sqrt)] {
        assert!(w.libm < NEEDED, "libm {name}: {}", w.libm);
        assert!(w.micromath > 100.0 * NEEDED, "micromath {name} is now within {}: revisit the choice", w.micromath);
    }
}
