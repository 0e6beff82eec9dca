//! Pose models trained apart joined into one ensemble (`tactrace
//! ensemble`): the members' nets one after the other, `config.ensemble`
//! of them, so a prediction averages the members' scaled outputs as an
//! ensemble's does ([`crate::ModelConfig::ensemble`]; a circular target's
//! sine and cosine averaged before its `atan2`, so 179 and -179 deg give
//! 180). Joined only when every member's nets see the same inputs and
//! answer in the same units: the same standardiser, target scaling,
//! targets, features, turned and mirrored views, and configurations that
//! differ in the schedule's length, seed and band weight only (the band
//! weight orders the training rows and changes nothing at prediction). So
//! the snapshots of one run (a model and its continuations, `train
//! --init`) and runs of other seeds or band weights on the same rows
//! join; models fitted on other rows (another standardiser) or of other
//! nets or rates do not.
use crate::config::ModelConfig;
use crate::error::LearnError;
use crate::fit_members::member_name;
use crate::member::single_name;
use crate::pose_model::{FittedNet, PoseModel};
use crate::setting_difference::{first_difference, SettingDifference};
use std::sync::OnceLock;

impl PoseModel {
    /// One ensemble of `members` (each a single model or an ensemble,
    /// whose members it keeps): their nets in order. Its configuration,
    /// seed, epochs and band weight are the first member's, with
    /// `ensemble` the count of members joined (so [`PoseModel::member`]
    /// gives each member's nets, but the seed, epochs and band weight it
    /// records are the first's); the
    /// caller keeps a record of every member. Error when there is no
    /// member, when any member differs from the first in what its nets
    /// see or answer (the module's documentation says what), or when the
    /// members are more than [`crate::MAX_ENSEMBLE`].
    pub fn join(members: &[PoseModel]) -> Result<PoseModel, LearnError> {
        let Some((first, rest)) = members.split_first() else {
            return Err(refused("no member to join".into()));
        };
        for (i, other) in rest.iter().enumerate() {
            check_joinable(first, other)
                .map_err(|why| refused(format!("member {} against member 1: {why}", i + 2)))?;
        }
        let k: usize = members.iter().map(|m| m.config.ensemble).sum();
        let config = ModelConfig {
            ensemble: k,
            ..first.config.clone()
        };
        config.validate()?;
        Ok(PoseModel {
            config,
            standardiser: first.standardiser.clone(),
            targets: first.targets.clone(),
            nets: joined_nets(members, k),
            outputs: first.outputs.clone(),
            features: first.features.clone(),
            views: first.views.clone(),
            mirror: first.mirror.clone(),
            epochs_before: first.epochs_before,
            predictor: OnceLock::new(),
        })
    }
}

/// Every member's nets in order, renamed as member `m` of `k` (`pose#m`).
fn joined_nets(members: &[PoseModel], k: usize) -> Vec<FittedNet> {
    let mut nets = Vec::new();
    let mut m = 0;
    for model in members {
        let own = model.config.ensemble;
        let per = model.nets.len() / own;
        for (slot, net) in model.nets.iter().enumerate() {
            let name = single_name(&net.name, own);
            nets.push(FittedNet {
                name: member_name(name, m + slot / per, k),
                ..net.clone()
            });
        }
        m += own;
    }
    nets
}

/// Why `other` cannot join `first` in one ensemble, as a message: they
/// differ in the targets, the standardiser of the inputs, the target
/// scaling, the features, the turned or mirrored views, or their
/// configurations in more than the epochs, seed, members, divergence
/// retries and band weight (the first differing key named).
pub(crate) fn check_joinable(first: &PoseModel, other: &PoseModel) -> Result<(), String> {
    if first.outputs != other.outputs {
        return Err("they predict other targets".into());
    }
    if first.standardiser != other.standardiser {
        return Err(
            "their inputs are standardised otherwise (fitted on other rows or \
                    features): a member's nets take the inputs in its own units"
                .into(),
        );
    }
    if first.targets != other.targets {
        return Err("their targets are scaled otherwise (fitted on other rows)".into());
    }
    if first.features != other.features || first.views != other.views {
        return Err("their nets see other features or turned views".into());
    }
    if first.mirror != other.mirror {
        return Err("their nets see other mirror views".into());
    }
    let (a, b) = (
        nets_and_rates(&first.config)?,
        nets_and_rates(&other.config)?,
    );
    match first_difference(&a, &b) {
        None => Ok(()),
        Some(SettingDifference { key, was, now }) => Err(format!(
            "`{key}` is {was} in member 1 and {now} in this one: members may differ only in their \
             seed, epochs and band weight"
        )),
    }
}

/// `cfg` as JSON with what members may differ in set to fixed values.
fn nets_and_rates(cfg: &ModelConfig) -> Result<serde_json::Value, String> {
    let c = ModelConfig {
        epochs: 1,
        seed: 0,
        ensemble: 1,
        divergence_retries: 0,
        band_weight: None,
        ..cfg.clone()
    };
    serde_json::to_value(&c).map_err(|e| e.to_string())
}

fn refused(reason: String) -> LearnError {
    LearnError::Config {
        field: "ensemble",
        reason,
    }
}

#[cfg(test)]
mod tests {
    use crate::config::{ModelConfig, ModelKind, Preset};
    use crate::member::tests::{angle_model, constant_net};
    use crate::pose_model::PoseModel;
    use crate::targets::{wrap_deg, ModelTarget};

    /// A single DisDenNN of one circular angle whose net predicts `angle`
    /// (deg) whatever the input, its inputs standardised by `mean`.
    fn constant_angle(angle: f64, mean: f64) -> PoseModel {
        let mut config = ModelConfig::preset(ModelKind::DisDenNN, Preset::Default);
        config.pose.as_mut().expect("pose").hidden = vec![1];
        config.validate().expect("config");
        let r = angle.to_radians();
        let out = [r.sin() as f32, r.cos() as f32];
        angle_model(config, vec![constant_net("pose", 4, out)], mean)
    }

    fn angle_of(model: &PoseModel) -> f64 {
        model
            .predict_targets(&[0.3, -1.0, 2.0, 0.0])
            .expect("predict")[0]
    }

    #[test]
    fn joined_angles_average_as_vectors_across_the_wrap() {
        // 179 and -179 deg: the circular mean is 180, the numbers' mean 0.
        for (angles, mean) in [([179.0, -179.0], 180.0), ([-170.0, 150.0], 170.0)] {
            let members = angles.map(|a| constant_angle(a, 0.0));
            let joined = PoseModel::join(&members).expect("join");
            let (json, weights) = joined.to_bytes().expect("save");
            let loaded = PoseModel::from_bytes(&json, &weights).expect("load");
            for m in [&joined, &loaded] {
                let off = wrap_deg(angle_of(m) - mean).abs();
                assert!(off < 1e-4, "{angles:?}: {} deg, want {mean}", angle_of(m));
            }
            let names: Vec<&str> = joined.nets.iter().map(|n| n.name.as_str()).collect();
            assert_eq!(names, ["pose#1", "pose#2"]);
            for (k, want) in angles.iter().enumerate() {
                let off = wrap_deg(angle_of(&joined.member(k).expect("member")) - want);
                assert!(off.abs() < 1e-4, "member {k}");
            }
        }
    }

    #[test]
    fn members_of_other_inputs_nets_or_rates_are_refused() {
        let one = constant_angle(10.0, 0.0);
        let refusal = |other: PoseModel| {
            let e = PoseModel::join(&[one.clone(), other]).expect_err("refused");
            e.to_string()
        };
        let moved = refusal(constant_angle(10.0, 0.5));
        assert!(
            moved.contains("member 2") && moved.contains("standardised"),
            "{moved}"
        );
        let mut faster = one.clone();
        faster.config.scale_learning_rates(2.0);
        assert!(refusal(faster).contains("learning_rate"));
        let mut other = one.clone();
        other.outputs = vec![ModelTarget::circular("pose_5")];
        assert!(refusal(other).contains("other targets"));
        assert!(PoseModel::join(&[]).is_err());
        // What members may differ in: the seed, the epochs and the band
        // weight (the rows' order in training; nothing at prediction).
        let mut later = one.clone();
        later.config.seed = 9;
        later.config.epochs += 30;
        later.config.band_weight = Some(crate::BandWeight {
            target: "pose_2".into(),
            min: Some(5.0),
            max: None,
            weight: 2,
        });
        assert_eq!(
            PoseModel::join(&[one, later])
                .expect("join")
                .config
                .ensemble,
            2
        );
    }
}
