//! The simulated arm: reaches commanded poses up to a repeatability error.
//!
//! The controller only ever sees the commanded pose ([`Arm::pose`]), as it
//! would on a real UR5. The pose physically reached (commanded + noise) is
//! published through a [`PoseProbe`] that only the simulated sensor holds:
//! it is how the simulated world knows where the dome really is.
use crate::{Arm, ArmError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::sync::{Arc, Mutex, PoisonError};
use tactrace_geometry::Pose;

/// Settings of the simulated arm.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimArmConfig {
    /// Standard deviation of the isotropic position error of each move, mm
    /// (applied independently to x, y and z).
    pub repeatability_mm: f64,
    /// Standard deviation of the yaw (rz) error of each move, degrees: a
    /// turn about the work frame's z axis, so a tilted (6-DoF) pose keeps
    /// its tilt exactly and its orientation is off by this angle.
    pub repeatability_deg: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl Default for SimArmConfig {
    fn default() -> Self {
        Self {
            repeatability_mm: 0.02,
            repeatability_deg: 0.02,
            seed: 0,
        }
    }
}

impl SimArmConfig {
    /// Check that the noise levels are finite and non-negative.
    pub fn validate(&self) -> Result<(), ArmError> {
        let check = |field, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(ArmError::InvalidConfig {
                    field,
                    value,
                    reason: "must be finite and >= 0",
                })
            }
        };
        check("repeatability_mm", self.repeatability_mm)?;
        check("repeatability_deg", self.repeatability_deg)
    }
}

/// Read-only handle on the pose the simulated arm physically reached.
///
/// Cheap to clone, `Send + Sync`; give it to the simulated world only.
#[derive(Debug, Clone)]
pub struct PoseProbe {
    actual: Arc<Mutex<Pose>>,
}

impl PoseProbe {
    /// The pose physically reached by the last move (work frame, mm/deg).
    pub fn actual(&self) -> Pose {
        *self.actual.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// A simulated UR5-class arm.
#[derive(Debug)]
pub struct SimArm {
    config: SimArmConfig,
    rng: ChaCha8Rng,
    commanded: Pose,
    actual: Arc<Mutex<Pose>>,
    moves: u64,
}

impl SimArm {
    /// An arm resting exactly at `start` (no noise on the initial pose).
    ///
    /// An invalid configuration (see [`SimArmConfig::validate`]) is not an
    /// error here; every [`Arm::move_to`] then returns it.
    pub fn new(config: SimArmConfig, start: Pose) -> Self {
        let rng = ChaCha8Rng::seed_from_u64(config.seed);
        Self {
            config,
            rng,
            commanded: start,
            actual: Arc::new(Mutex::new(start)),
            moves: 0,
        }
    }

    /// An arm as [`SimArm::new`] and the one handle on its physically
    /// reached pose, for the simulated world (the sensor) only. The arm
    /// itself shows only its commanded pose: the true pose cannot be read
    /// from it, so code that holds the arm cannot leak it to a controller.
    pub fn with_probe(config: SimArmConfig, start: Pose) -> (Self, PoseProbe) {
        let arm = Self::new(config, start);
        let probe = PoseProbe {
            actual: Arc::clone(&arm.actual),
        };
        (arm, probe)
    }

    /// Number of completed moves (taps count as two).
    pub fn moves(&self) -> u64 {
        self.moves
    }

    /// The configuration the arm runs with.
    pub fn config(&self) -> &SimArmConfig {
        &self.config
    }

    /// `pose` perturbed by the repeatability error (x, y, z and rz; rz is
    /// the last extrinsic angle, so the turn is about the work z axis at
    /// any tilt).
    fn perturb(&mut self, pose: Pose) -> Pose {
        let mut gauss = |sd: f64| sd * self.rng.sample::<f64, _>(StandardNormal);
        let (sd_mm, sd_deg) = (self.config.repeatability_mm, self.config.repeatability_deg);
        Pose {
            x: pose.x + gauss(sd_mm),
            y: pose.y + gauss(sd_mm),
            z: pose.z + gauss(sd_mm),
            rz: pose.rz + gauss(sd_deg),
            ..pose
        }
    }
}

impl Arm for SimArm {
    fn move_to(&mut self, pose: Pose) -> Result<(), ArmError> {
        self.config.validate()?;
        if !pose.is_finite() {
            return Err(ArmError::NonFinitePose { pose });
        }
        let reached = self.perturb(pose);
        self.commanded = pose;
        *self.actual.lock().unwrap_or_else(PoisonError::into_inner) = reached;
        self.moves += 1;
        Ok(())
    }

    fn pose(&self) -> Pose {
        self.commanded
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commanded_pose_is_exact_and_actual_is_noisy() {
        let cfg = SimArmConfig {
            repeatability_mm: 0.05,
            repeatability_deg: 0.1,
            seed: 9,
        };
        let (mut arm, probe) = SimArm::with_probe(cfg, Pose::default());
        assert_eq!(probe.actual(), Pose::default(), "start pose is exact");
        let n = 20_000;
        let (mut sum, mut sum2, mut sum_rz2) = ([0.0; 3], [0.0; 3], 0.0);
        for i in 0..n {
            let target = Pose::planar(i as f64 * 0.01, 5.0, 2.0, 30.0);
            arm.move_to(target).unwrap();
            assert_eq!(arm.pose(), target);
            let a = probe.actual();
            assert_eq!((a.rx, a.ry), (0.0, 0.0), "roll and pitch are exact");
            let err = [a.x - target.x, a.y - target.y, a.z - target.z];
            for k in 0..3 {
                sum[k] += err[k];
                sum2[k] += err[k] * err[k];
            }
            sum_rz2 += (a.rz - 30.0).powi(2);
        }
        assert_eq!(arm.moves(), n);
        // Sample std of a Gaussian: relative standard error 1/sqrt(2n) = 0.5 %.
        for k in 0..3 {
            let mean = sum[k] / n as f64;
            let sd = (sum2[k] / n as f64 - mean * mean).sqrt();
            assert!(
                mean.abs() < 4.0 * 0.05 / (n as f64).sqrt(),
                "axis {k} mean {mean}"
            );
            assert!((sd / 0.05 - 1.0).abs() < 0.03, "axis {k} sd {sd}");
        }
        let sd_rz = (sum_rz2 / n as f64).sqrt();
        assert!((sd_rz / 0.1 - 1.0).abs() < 0.03, "rz sd {sd_rz}");
    }

    #[test]
    fn same_seed_same_noise() {
        let run = || {
            let (mut arm, probe) = SimArm::with_probe(SimArmConfig::default(), Pose::default());
            arm.move_to(Pose::planar(1.0, 2.0, 3.0, 4.0)).unwrap();
            probe.actual()
        };
        assert_eq!(run(), run());
    }

    #[test]
    fn taps_move_straight_down_and_up() {
        let start = Pose::planar(3.0, 4.0, 2.0, 10.0);
        let (mut arm, probe) = SimArm::with_probe(
            SimArmConfig {
                repeatability_mm: 0.0,
                repeatability_deg: 0.0,
                seed: 1,
            },
            start,
        );
        arm.tap_down(5.0).unwrap();
        assert_eq!(probe.actual(), Pose { z: -3.0, ..start });
        arm.tap_up(5.0).unwrap();
        assert_eq!(arm.pose(), start);
        assert_eq!(arm.moves(), 2);
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let mut arm = SimArm::new(
            SimArmConfig {
                repeatability_mm: -1.0,
                ..Default::default()
            },
            Pose::default(),
        );
        assert!(matches!(
            arm.move_to(Pose::default()),
            Err(ArmError::InvalidConfig { .. })
        ));
        let mut arm = SimArm::new(SimArmConfig::default(), Pose::default());
        let nan = Pose {
            x: f64::NAN,
            ..Pose::default()
        };
        assert!(matches!(
            arm.move_to(nan),
            Err(ArmError::NonFinitePose { .. })
        ));
        assert_eq!(arm.moves(), 0);
    }

    #[test]
    fn probe_is_send_and_sync() {
        fn check<T: Send + Sync + Clone>() {}
        check::<PoseProbe>();
    }
}
