//! The members of an ensemble ([`crate::ModelConfig::ensemble`]) one at a
//! time: each is the single model its seed gives, so an ensemble can be
//! taken apart and checked against models trained alone.
use crate::config::ModelConfig;
use crate::error::LearnError;
use crate::pose_model::{FittedNet, PoseModel};
use std::sync::OnceLock;

impl PoseModel {
    /// Member `m` (from 0) of the ensemble as a single model: its nets,
    /// the shared standardiser, PCA and target scaling, and the
    /// configuration with `ensemble = 1`, the member's seed
    /// ([`ModelConfig::member_seed`]) and the rates it trained with (its
    /// own halvings after a divergence applied); the model itself for
    /// `m = 0` of a single model. Error when `m` is not a member.
    pub fn member(&self, m: usize) -> Result<PoseModel, LearnError> {
        let k = self.config.ensemble;
        if m >= k {
            return Err(LearnError::Config {
                field: "ensemble",
                reason: format!("member {m} of an ensemble of {k}"),
            });
        }
        let per = self.nets.len() / k;
        let own = &self.nets[m * per..(m + 1) * per];
        let nets = own
            .iter()
            .map(|n| FittedNet {
                name: single_name(&n.name, k).to_string(),
                lr_halvings: 0,
                ..n.clone()
            })
            .collect();
        let mut config = ModelConfig {
            seed: self.config.member_seed(m),
            ensemble: 1,
            ..self.config.clone()
        };
        for _ in 0..own.first().map_or(0, |n| n.lr_halvings) {
            config.scale_learning_rates(0.5);
        }
        Ok(PoseModel {
            config,
            standardiser: self.standardiser.clone(),
            targets: self.targets.clone(),
            nets,
            outputs: self.outputs.clone(),
            features: self.features.clone(),
            views: self.views.clone(),
            mirror: self.mirror.clone(),
            epochs_before: self.epochs_before,
            predictor: OnceLock::new(),
        })
    }
}

impl PoseModel {
    /// How often each member's learning rates were halved after it
    /// diverged, beyond the configuration's rates (one entry a member; a
    /// single model's configuration holds its rates, so its entry is 0).
    pub fn member_lr_halvings(&self) -> Vec<usize> {
        let k = self.config.ensemble;
        let per = self.nets.len() / k;
        (0..k).map(|m| self.nets[m * per].lr_halvings).collect()
    }
}

/// A member's net name without its `#m` (the name trained alone).
pub(crate) fn single_name(name: &str, k: usize) -> &str {
    match name.rsplit_once('#') {
        Some((base, _)) if k > 1 => base,
        _ => name,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use crate::config::{ModelConfig, ModelKind, Preset};
    use crate::net::Layers;
    use crate::pose_model::{FittedNet, PoseModel};
    use crate::standardise::Standardiser;
    use crate::targets::{wrap_deg, ModelTarget};

    /// A net of `dim` inputs whose output is `out` whatever the input
    /// (zero weights, the output layer's biases `out`).
    pub(crate) fn constant_net(name: &str, dim: usize, out: [f32; 2]) -> FittedNet {
        let sizes = vec![dim, 1, 2];
        let w = vec![vec![0.0; dim], vec![0.0; 2]];
        let b = vec![vec![0.0], out.to_vec()];
        FittedNet {
            name: name.into(),
            targets: vec![0, 1],
            pca: None,
            layers: Layers::from_parts(sizes, w, b).expect("layers"),
            lr_halvings: 0,
        }
    }

    /// An ensemble of two DisDenNN members of one circular angle, each
    /// net predicting the constant `angles[m]` (deg), targets unscaled.
    fn two_members(angles: [f64; 2]) -> PoseModel {
        let mut config = ModelConfig::preset(ModelKind::DisDenNN, Preset::Default);
        config.ensemble = 2;
        config.pose.as_mut().expect("pose").hidden = vec![1];
        config.validate().expect("config");
        let dim = 4;
        let nets = angles
            .iter()
            .enumerate()
            .map(|(m, a)| {
                let r = a.to_radians();
                let out = [r.sin() as f32, r.cos() as f32];
                constant_net(&format!("pose#{}", m + 1), dim, out)
            })
            .collect();
        angle_model(config, nets, 0.0)
    }

    /// A model of one circular angle (`pose_6`, targets unscaled) of
    /// `nets` on 4 inputs standardised by `mean` (spread 1).
    pub(crate) fn angle_model(config: ModelConfig, nets: Vec<FittedNet>, mean: f64) -> PoseModel {
        let dim = 4;
        PoseModel {
            config,
            standardiser: Standardiser::from_parts(vec![mean; dim], vec![1.0; dim]).expect("std"),
            targets: Standardiser::from_parts(vec![0.0; 2], vec![1.0; 2]).expect("targets"),
            nets,
            outputs: vec![ModelTarget::circular("pose_6")],
            features: None,
            views: None,
            mirror: None,
            epochs_before: 0,
            predictor: Default::default(),
        }
    }

    #[test]
    fn an_ensembles_circular_target_averages_across_the_wrap() {
        // 179 and -179 deg: the circular mean is 180, the mean of the
        // numbers 0. Also off the wrap, and after a save and load.
        for (angles, mean) in [([179.0, -179.0], 180.0), ([-170.0, 150.0], 170.0)] {
            let model = two_members(angles);
            let (json, weights) = model.to_bytes().expect("save");
            let loaded = PoseModel::from_bytes(&json, &weights).expect("load");
            for m in [&model, &loaded] {
                let got = m.predict_targets(&[0.3, -1.0, 2.0, 0.0]).expect("predict")[0];
                let off = wrap_deg(got - mean).abs();
                assert!(off < 1e-4, "{angles:?}: {got} deg, want {mean}");
            }
            for (k, want) in angles.iter().enumerate() {
                let one = model.member(k).expect("member");
                let got = one.predict_targets(&[0.0; 4]).expect("member")[0];
                assert!(wrap_deg(got - want).abs() < 1e-4, "member {k}: {got}");
                assert_eq!(one.nets[0].name, "pose");
            }
        }
        assert!(two_members([0.0, 1.0]).member(2).is_err());
    }
}
