//! What the tuning searches: the controller's gains, the tangential step
//! and the policy's settings (issue 12), each scaled to [0, 1] between
//! bounds so one step size suits them all.
use tactrace_control::PbtsConfig;

/// One tuned setting: its name in `tuned.toml` and its search bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knob {
    /// Where it lives in the `[controller]` table.
    pub name: &'static str,
    /// Search bounds (the setting's units).
    pub lo: f64,
    pub hi: f64,
}

/// The tuned settings, in search order.
pub const KNOBS: [Knob; 13] = [
    knob("reference[1] (step, mm)", 0.5, 2.0),
    knob("kp[0] (x)", 0.1, 1.0),
    knob("ki[0] (x)", 0.0, 0.6),
    knob("kd[0] (x)", 0.0, 0.6),
    knob("kp[5] (rz)", 0.1, 1.0),
    knob("ki[5] (rz)", 0.0, 0.4),
    knob("kd[5] (rz)", 0.0, 0.6),
    knob("policy.curvature_offset_mm2", 0.0, 30.0),
    knob("policy.max_offset_mm", 0.5, 5.0),
    knob("policy.curvature_smoothing", 0.05, 1.0),
    knob("policy.step_curvature_mm", 0.0, 40.0),
    knob("1 / policy.step_angle_deg (1/deg)", 0.0, 0.3),
    knob("policy.min_step_fraction", 0.1, 1.0),
];

const fn knob(name: &'static str, lo: f64, hi: f64) -> Knob {
    Knob { name, lo, hi }
}

/// Below this, 1 / step_angle_deg counts as 0 (the angle term off).
const ANGLE_OFF: f64 = 1e-3;

/// The value of knob `i` in `c`.
fn get(c: &PbtsConfig, i: usize) -> f64 {
    let p = &c.policy;
    match i {
        0 => c.reference[1],
        1 => c.kp[0],
        2 => c.ki[0],
        3 => c.kd[0],
        4 => c.kp[5],
        5 => c.ki[5],
        6 => c.kd[5],
        7 => p.curvature_offset_mm2,
        8 => p.max_offset_mm,
        9 => p.curvature_smoothing,
        10 => p.step_curvature_mm,
        11 if p.step_angle_deg > 0.0 => 1.0 / p.step_angle_deg,
        11 => 0.0,
        _ => p.min_step_fraction,
    }
}

/// Set knob `i` of `c` to `v`.
fn set(c: &mut PbtsConfig, i: usize, v: f64) {
    let p = &mut c.policy;
    match i {
        0 => c.reference[1] = v,
        1 => c.kp[0] = v,
        2 => c.ki[0] = v,
        3 => c.kd[0] = v,
        4 => c.kp[5] = v,
        5 => c.ki[5] = v,
        6 => c.kd[5] = v,
        7 => p.curvature_offset_mm2 = v,
        8 => p.max_offset_mm = v,
        9 => p.curvature_smoothing = v,
        10 => p.step_curvature_mm = v,
        11 => p.step_angle_deg = if v < ANGLE_OFF { 0.0 } else { 1.0 / v },
        _ => p.min_step_fraction = v,
    }
}

/// `c`'s tuned settings scaled to [0, 1] (clamped to the bounds).
pub fn to_unit(c: &PbtsConfig) -> Vec<f64> {
    KNOBS
        .iter()
        .enumerate()
        .map(|(i, k)| ((get(c, i) - k.lo) / (k.hi - k.lo)).clamp(0.0, 1.0))
        .collect()
}

/// `base` with the tuned settings taken from the unit point `u` (each
/// clamped to [0, 1]), and the squared distance `u` lay outside the box:
/// the search's boundary penalty.
pub fn from_unit(base: &PbtsConfig, u: &[f64]) -> (PbtsConfig, f64) {
    let mut c = base.clone();
    let mut outside = 0.0;
    for (i, (k, &v)) in KNOBS.iter().zip(u).enumerate() {
        let inside = v.clamp(0.0, 1.0);
        outside += (v - inside).powi(2);
        set(&mut c, i, k.lo + inside * (k.hi - k.lo));
    }
    (c, outside)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_unit_point_maps_back_to_the_same_settings() {
        let u: Vec<f64> = (0..KNOBS.len()).map(|i| (i as f64 + 0.5) / 14.0).collect();
        let (c, outside) = from_unit(&PbtsConfig::default(), &u);
        assert_eq!(outside, 0.0);
        c.validate().unwrap();
        for (a, b) in to_unit(&c).iter().zip(&u) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
        let (clamped, outside) = from_unit(&PbtsConfig::default(), &vec![1.5; KNOBS.len()]);
        assert!((outside - 0.25 * KNOBS.len() as f64).abs() < 1e-12);
        assert_eq!(clamped.kp[0], 1.0);
    }

    #[test]
    fn the_report_controller_is_inside_the_box() {
        let report = PbtsConfig::default();
        let (back, outside) = from_unit(&report, &to_unit(&report));
        assert_eq!(outside, 0.0);
        for (i, knob) in KNOBS.iter().enumerate() {
            assert!(
                (get(&back, i) - get(&report, i)).abs() < 1e-12,
                "{}",
                knob.name
            );
        }
        assert_eq!(back.policy.step_angle_deg, 0.0);
    }
}
