//! The pins' detection noise estimated from the taps' scatter about a
//! smooth field (docs/calibration.md, "Pin jitter fitted from the
//! taps"), checked against its theory on a 127-pin hexagonal lattice: a
//! quadratic field has no roughness (the stencil is exact for it); a
//! smooth field with independent Gaussian noise of standard deviation
//! sigma per pin and axis has roughness sigma; a fixed error per pin
//! (the reference frame's own) adds none. The jitter fit inverts a
//! curve of the form `q(s)^2 = q0^2 + s^2` exactly.
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use tactrace_calib::{
    fit_jitter, roughness, CalibError, Fields, JitterPoint, Stencil, JITTER_GRID,
};
use tactrace_testdata::layouts::hex_lattice;

const TAPS: usize = 100;

/// `TAPS` smooth fields over `rest`: a random quadratic each (per axis)
/// plus, when `bump`, a Gaussian bump one fifth of the dome wide (not a
/// quadratic), with `noise` px of Gaussian noise per pin and axis and a
/// fixed error per pin of `fixed` px.
fn fields(rest: &[[f64; 2]], bump: bool, noise: f64, fixed: f64, seed: u64) -> Fields {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).unwrap();
    let p = rest.len();
    let offsets: Vec<f64> = (0..2 * p).map(|_| fixed * unit.sample(&mut rng)).collect();
    let rows: Vec<Vec<f32>> = (0..TAPS)
        .map(|_| {
            let c: Vec<f64> = (0..12).map(|_| unit.sample(&mut rng)).collect();
            let centre = [unit.sample(&mut rng) * 20.0, unit.sample(&mut rng) * 20.0];
            (0..2 * p)
                .map(|k| {
                    let [x, y] = rest[k % p];
                    let (u, v) = ((x - 128.0) / 60.0, (y - 128.0) / 60.0);
                    let a = if k < p { 0 } else { 6 };
                    let mut f = c[a] + c[a + 1] * u + c[a + 2] * v;
                    f += c[a + 3] * u * u + c[a + 4] * u * v + c[a + 5] * v * v;
                    if bump {
                        let (dx, dy) = (x - 128.0 - centre[0], y - 128.0 - centre[1]);
                        f += 2.0 * (-(dx * dx + dy * dy) / (2.0 * 25.0f64.powi(2))).exp();
                    }
                    (f + offsets[k] + noise * unit.sample(&mut rng)) as f32
                })
                .collect()
        })
        .collect();
    Fields::from_rows(&rows, "synthetic taps").unwrap()
}

fn lattice() -> Vec<[f64; 2]> {
    hex_lattice([128.0, 128.0], 18.0, 6)
}

#[test]
fn a_quadratic_field_has_no_roughness() {
    let rest = lattice();
    let stencil = Stencil::new(&rest).unwrap();
    assert_eq!(stencil.len(), 127, "every pin's neighbours fix a quadratic");
    let q = roughness(&fields(&rest, false, 0.0, 0.0, 1), &stencil).unwrap();
    assert!(q < 1e-6, "roughness {q} px");
}

#[test]
fn the_roughness_of_a_noisy_smooth_field_is_its_noise() {
    let rest = lattice();
    let stencil = Stencil::new(&rest).unwrap();
    for (sigma, seed) in [(0.1, 2), (0.2, 3), (0.4, 4)] {
        let q = roughness(&fields(&rest, true, sigma, 0.0, seed), &stencil).unwrap();
        assert!(
            (q / sigma - 1.0).abs() < 0.08,
            "sigma {sigma}: roughness {q}"
        );
    }
    // Without noise the bump's own curvature is what is left: small.
    let q0 = roughness(&fields(&rest, true, 0.0, 0.0, 5), &stencil).unwrap();
    assert!(q0 < 0.03, "noiseless bump: {q0}");
}

#[test]
fn a_fixed_error_per_pin_adds_no_roughness() {
    let rest = lattice();
    let stencil = Stencil::new(&rest).unwrap();
    let plain = roughness(&fields(&rest, true, 0.2, 0.0, 6), &stencil).unwrap();
    let fixed = roughness(&fields(&rest, true, 0.2, 0.5, 6), &stencil).unwrap();
    assert!((fixed - plain).abs() < 0.01, "{plain} -> {fixed}");
}

#[test]
fn the_fit_inverts_a_curve_of_added_variance() {
    let q0 = 0.12;
    let curve: Vec<JitterPoint> = JITTER_GRID
        .iter()
        .map(|&s| JitterPoint {
            jitter_px: s,
            roughness_px: (q0 * q0 + s * s).sqrt(),
        })
        .collect();
    for s in [0.07, 0.15, 0.25, 0.5] {
        let got = fit_jitter((q0 * q0 + s * s).sqrt(), &curve, TAPS).unwrap();
        assert!((got.pin_jitter_px - s).abs() < 1e-9, "{s}: {got:?}");
        assert!(!got.beyond_grid);
    }
    let none = fit_jitter(0.9 * q0, &curve, TAPS).unwrap();
    assert_eq!(
        none.pin_jitter_px, 0.0,
        "no rougher than the noiseless renders"
    );
    let above = fit_jitter(2.0, &curve, TAPS).unwrap();
    assert!(above.beyond_grid && above.pin_jitter_px == 1.0);
    let mut falling = curve.clone();
    falling.swap(1, 2);
    let err = fit_jitter(0.2, &falling, TAPS).unwrap_err();
    assert!(matches!(err, CalibError::Param(_)), "{err}");
}

#[test]
fn too_few_pins_or_taps_are_refused() {
    let rest = lattice();
    assert!(matches!(
        Stencil::new(&rest[..10]),
        Err(CalibError::Dimension { .. })
    ));
    let stencil = Stencil::new(&rest).unwrap();
    let one = fields(&rest, false, 0.1, 0.0, 7).subset(&[0]);
    assert!(matches!(
        roughness(&one, &stencil),
        Err(CalibError::TooFewTaps { .. })
    ));
}
