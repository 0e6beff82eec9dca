//! What a pose model predicts: N named targets, each in millimetres or
//! degrees, an angle possibly circular (over the full circle, its errors
//! wrapping at +-180 deg). A circular target reaches the networks as two
//! columns, its sine and cosine, and is read back by `atan2`, so a net
//! never has to jump from +180 to -180; every other target is one column.
//! The encoded columns are then scaled by their spread (the model's target
//! standardiser), so mm and degrees weigh alike.
use crate::error::LearnError;
use serde::{Deserialize, Serialize};

/// The unit of a target (millimetres and degrees at every public boundary).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Unit {
    /// Millimetres: a position or a depth.
    Mm,
    /// Degrees: an angle.
    Deg,
}

impl Unit {
    /// Its name as written in files (`mm`, `deg`).
    pub fn as_str(self) -> &'static str {
        match self {
            Unit::Mm => "mm",
            Unit::Deg => "deg",
        }
    }
}

/// What a target is to the servo loop of an edge task: the edge's
/// position (the controller's r, mm) or its angle (theta, deg). A model
/// whose targets are one position and one angle needs no role; one that
/// also predicts, say, the tap's depth (a second target in mm) marks which
/// target is which, so the loop reads the edge pose from it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// The edge's position, r (mm).
    Position,
    /// The edge's angle, theta (deg).
    Angle,
}

impl Role {
    /// Its name as written in files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Position => "position",
            Role::Angle => "angle",
        }
    }

    /// The role named `text` (`position`, `angle`), if it is one.
    pub fn parse(text: &str) -> Option<Self> {
        match text {
            "position" => Some(Role::Position),
            "angle" => Some(Role::Angle),
            _ => None,
        }
    }

    /// The unit a target in this role is in.
    pub fn unit(self) -> Unit {
        match self {
            Role::Position => Unit::Mm,
            Role::Angle => Unit::Deg,
        }
    }
}

/// One target a model predicts: its name (the labels column), unit,
/// whether it is circular, and its role in an edge task, if marked.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelTarget {
    /// The target's name (its column in the labels file).
    pub name: String,
    /// Millimetres or degrees.
    pub unit: Unit,
    /// An angle over the full circle: learnt as (sin, cos), errors wrapped.
    #[serde(default)]
    pub circular: bool,
    /// The edge pose's position or angle, when marked ([`Role`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub role: Option<Role>,
}

impl ModelTarget {
    /// A target that is not circular.
    pub fn new(name: impl Into<String>, unit: Unit) -> Self {
        Self {
            name: name.into(),
            unit,
            circular: false,
            role: None,
        }
    }

    /// A circular angle (degrees).
    pub fn circular(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            unit: Unit::Deg,
            circular: true,
            role: None,
        }
    }

    /// The same target marked as the edge pose's `role`.
    pub fn with_role(self, role: Role) -> Self {
        Self {
            role: Some(role),
            ..self
        }
    }

    /// Columns it takes at the networks: 2 (sin, cos) when circular, else 1.
    pub fn width(&self) -> usize {
        if self.circular {
            2
        } else {
            1
        }
    }

    /// The absolute error of `predicted` against `truth`, wrapped into
    /// [0, 180] deg when circular (179 against -179 is 2 deg).
    pub fn abs_error(&self, predicted: f64, truth: f64) -> f64 {
        let d = predicted - truth;
        if self.circular {
            wrap_deg(d).abs()
        } else {
            d.abs()
        }
    }
}

/// `deg` wrapped into (-180, 180].
pub fn wrap_deg(deg: f64) -> f64 {
    let w = (deg + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 {
        180.0
    } else {
        w
    }
}

/// The edge task's two targets, as every model before named targets had:
/// `r` (mm) and `theta` (deg, not circular).
pub fn edge_targets() -> Vec<ModelTarget> {
    vec![
        ModelTarget::new("r", Unit::Mm),
        ModelTarget::new("theta", Unit::Deg),
    ]
}

/// Whether `targets` are the edge task's own: `r` (mm) and `theta` (deg)
/// as [`edge_targets`] names them, or `r_mm` and `theta_deg` as
/// `collect`'s datasets (and arrays given without names) do. Only then do
/// outputs call them "position" and "angle"; any other model, a
/// surface's depth (mm) and angle (deg) included, is labelled by its
/// targets' names.
pub fn names_the_edge(targets: &[ModelTarget]) -> bool {
    let edge = |r: &str, theta: &str| {
        targets
            == [
                ModelTarget::new(r, Unit::Mm),
                ModelTarget::new(theta, Unit::Deg),
            ]
    };
    edge("r", "theta") || edge("r_mm", "theta_deg")
}

/// Error unless `targets` names at least one target, each name once, only
/// angles are circular, and each role is marked at most once, on a target
/// in its unit.
pub fn check_targets(targets: &[ModelTarget]) -> Result<(), LearnError> {
    if targets.is_empty() {
        return Err(LearnError::Targets {
            reason: "a model needs at least one target".into(),
        });
    }
    for (k, t) in targets.iter().enumerate() {
        if targets[..k].iter().any(|o| o.name == t.name) {
            return Err(LearnError::Targets {
                reason: format!("the target `{}` is named twice", t.name),
            });
        }
        if t.circular && t.unit != Unit::Deg {
            return Err(LearnError::Targets {
                reason: format!("the target `{}` is circular but not in degrees", t.name),
            });
        }
        check_role(targets, k)?;
    }
    Ok(())
}

/// Error unless the role of `targets[k]`, if any, matches its unit and
/// is not marked on an earlier target.
fn check_role(targets: &[ModelTarget], k: usize) -> Result<(), LearnError> {
    let t = &targets[k];
    let Some(role) = t.role else {
        return Ok(());
    };
    let reason = if t.unit != role.unit() {
        format!(
            "the target `{}` is marked as the edge's {} but is in {}, not {}",
            t.name,
            role.as_str(),
            t.unit.as_str(),
            role.unit().as_str()
        )
    } else if let Some(o) = targets[..k].iter().find(|o| o.role == Some(role)) {
        format!(
            "`{}` and `{}` are both marked {}",
            o.name,
            t.name,
            role.as_str()
        )
    } else {
        return Ok(());
    };
    Err(LearnError::Targets { reason })
}

/// The indices of the edge pose's position (mm) and angle (deg) among
/// `outputs`, as the servo loop reads them: the targets marked
/// [`Role::Position`] and [`Role::Angle`] when any is marked, else the two
/// targets of a model of exactly one position and one angle.
pub fn edge_roles(outputs: &[ModelTarget]) -> Result<[usize; 2], LearnError> {
    let marked = outputs.iter().any(|t| t.role.is_some());
    let find = |pick: &dyn Fn(&ModelTarget) -> bool| {
        let mut it = outputs.iter().enumerate().filter(|(_, t)| pick(t));
        match (it.next(), it.next()) {
            (Some((k, _)), None) => Some(k),
            _ => None,
        }
    };
    let found = if marked {
        (
            find(&|t| t.role == Some(Role::Position)),
            find(&|t| t.role == Some(Role::Angle)),
        )
    } else if outputs.len() == 2 {
        (
            find(&|t| t.unit == Unit::Mm),
            find(&|t| t.unit == Unit::Deg),
        )
    } else {
        (None, None)
    };
    match found {
        (Some(r), Some(theta)) => Ok([r, theta]),
        _ => Err(LearnError::NotAnEdgeModel {
            targets: outputs
                .iter()
                .map(|t| {
                    let role = t
                        .role
                        .map_or(String::new(), |r| format!(", {}", r.as_str()));
                    format!("{} ({}{role})", t.name, t.unit.as_str())
                })
                .collect::<Vec<_>>()
                .join(", "),
        }),
    }
}

/// The encoded column of the plain (not circular) target `name` of
/// `outputs`, for a setting that picks one (`band_weight`, `cost`); the
/// reason when it is not one of them, or is circular (`why_not_circular`
/// says why that will not do).
pub(crate) fn linear_column(
    outputs: &[ModelTarget],
    name: &str,
    why_not_circular: &str,
) -> Result<usize, String> {
    let Some(t) = outputs.iter().position(|o| o.name == name) else {
        let names: Vec<&str> = outputs.iter().map(|o| o.name.as_str()).collect();
        return Err(format!(
            "target `{name}` is not one of the model's ({})",
            names.join(", ")
        ));
    };
    if outputs[t].circular {
        return Err(format!("target `{name}` is circular: {why_not_circular}"));
    }
    Ok(encoded_columns(outputs)[t][0])
}

/// The encoded columns of each target, in order (`[k]` for a plain target,
/// `[k, k + 1]` for a circular one's sine and cosine).
pub fn encoded_columns(targets: &[ModelTarget]) -> Vec<Vec<usize>> {
    let mut next = 0;
    targets
        .iter()
        .map(|t| {
            let cols: Vec<usize> = (next..next + t.width()).collect();
            next += t.width();
            cols
        })
        .collect()
}

/// One sample's targets (`values`, in the targets' units) as the networks'
/// columns, appended to `out`.
pub fn encode_into(targets: &[ModelTarget], values: &[f32], out: &mut Vec<f32>) {
    for (t, &v) in targets.iter().zip(values) {
        if t.circular {
            let a = f64::from(v).to_radians();
            out.push(a.sin() as f32);
            out.push(a.cos() as f32);
        } else {
            out.push(v);
        }
    }
}

/// The networks' columns (unscaled) back to the targets' values: a
/// circular target by `atan2(sin, cos)`, in degrees within (-180, 180].
pub fn decode(targets: &[ModelTarget], encoded: &[f64]) -> Vec<f64> {
    let mut k = 0;
    targets
        .iter()
        .map(|t| {
            let v = if t.circular {
                wrap_deg(encoded[k].atan2(encoded[k + 1]).to_degrees())
            } else {
                encoded[k]
            };
            k += t.width();
            v
        })
        .collect()
}

/// Mean absolute error of each target over the rows of `pred` and
/// `truth` (rows of N values each, in the targets' units), circular ones
/// wrapped. Rows beyond the shorter input are ignored; none gives NaN.
pub fn target_mae(targets: &[ModelTarget], pred: &[Vec<f64>], truth: &[Vec<f64>]) -> Vec<f64> {
    let n = pred.len().min(truth.len());
    let mut sum = vec![0.0; targets.len()];
    for (p, t) in pred.iter().zip(truth).take(n) {
        for (j, target) in targets.iter().enumerate() {
            sum[j] += target.abs_error(p[j], t[j]);
        }
    }
    sum.into_iter().map(|s| s / n as f64).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_edge_tasks_own_names_are_an_edge() {
        assert!(names_the_edge(&edge_targets()));
        let named = |a: &str, b: &str| {
            [
                ModelTarget::new(a, Unit::Mm),
                ModelTarget::new(b, Unit::Deg),
            ]
        };
        assert!(names_the_edge(&named("r_mm", "theta_deg")));
        // A surface's depth and angle: one mm and one deg, not an edge.
        assert!(!names_the_edge(&named("pose_2", "pose_6")));
        let swapped = [
            ModelTarget::new("theta", Unit::Deg),
            ModelTarget::new("r", Unit::Mm),
        ];
        assert!(!names_the_edge(&swapped));
        let circular = [
            ModelTarget::new("r", Unit::Mm),
            ModelTarget::circular("theta"),
        ];
        assert!(!names_the_edge(&circular));
    }

    #[test]
    fn a_circular_target_round_trips_through_sin_and_cos() {
        let targets = vec![ModelTarget::new("d", Unit::Mm), ModelTarget::circular("a")];
        assert_eq!(encoded_columns(&targets), vec![vec![0], vec![1, 2]]);
        for deg in [-179.5f32, -90.0, 0.0, 45.0, 179.9, 180.0] {
            let mut enc = Vec::new();
            encode_into(&targets, &[1.5, deg], &mut enc);
            assert_eq!(enc.len(), 3);
            let enc: Vec<f64> = enc.iter().map(|&v| f64::from(v)).collect();
            let back = decode(&targets, &enc);
            assert!((back[0] - 1.5).abs() < 1e-6);
            assert!(
                targets[1].abs_error(back[1], f64::from(deg)) < 1e-4,
                "{deg} -> {back:?}"
            );
            assert!(back[1] > -180.0 && back[1] <= 180.0);
        }
    }

    #[test]
    fn wrapped_errors_of_circular_targets() {
        let a = ModelTarget::circular("a");
        assert!((a.abs_error(179.0, -179.0) - 2.0).abs() < 1e-12);
        assert!((a.abs_error(-170.0, 170.0) - 20.0).abs() < 1e-12);
        assert!((a.abs_error(10.0, 370.0)).abs() < 1e-12);
        assert_eq!(a.abs_error(90.0, -90.0), 180.0);
        let plain = ModelTarget::new("t", Unit::Deg);
        assert_eq!(plain.abs_error(179.0, -179.0), 358.0);
        let mae = target_mae(
            &[a, plain],
            &[vec![179.0, 1.0], vec![0.0, 3.0]],
            &[vec![-179.0, 0.0], vec![4.0, 0.0]],
        );
        assert_eq!(mae, vec![3.0, 2.0]);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(540.0), 180.0);
    }

    #[test]
    fn target_lists_are_checked() {
        assert!(check_targets(&[]).is_err());
        let twice = [
            ModelTarget::new("a", Unit::Mm),
            ModelTarget::new("a", Unit::Deg),
        ];
        assert!(check_targets(&twice).is_err());
        let mut mm = ModelTarget::new("a", Unit::Mm);
        mm.circular = true;
        assert!(check_targets(&[mm]).is_err());
        assert!(check_targets(&edge_targets()).is_ok());
    }

    #[test]
    fn the_edge_pose_is_read_from_marked_roles_beside_other_targets() {
        let (r, depth) = (
            ModelTarget::new("r", Unit::Mm),
            ModelTarget::new("d", Unit::Mm),
        );
        let theta = ModelTarget::circular("theta");
        // One position and one angle: no role needed, in either order.
        assert_eq!(edge_roles(&[r.clone(), theta.clone()]).unwrap(), [0, 1]);
        assert_eq!(edge_roles(&[theta.clone(), r.clone()]).unwrap(), [1, 0]);
        // A depth beside them: which mm target is the position is unknown.
        let three = [depth.clone(), theta.clone(), r.clone()];
        let err = edge_roles(&three).unwrap_err().to_string();
        assert!(err.contains(":position"), "{err}");
        // Marked, the roles decide, wherever the targets stand.
        let marked = [
            depth.clone(),
            theta.clone().with_role(Role::Angle),
            r.clone().with_role(Role::Position),
        ];
        assert!(check_targets(&marked).is_ok());
        assert_eq!(edge_roles(&marked).unwrap(), [2, 1]);
        // A role alone is not an edge pose.
        assert!(edge_roles(&[depth.clone(), r.clone().with_role(Role::Position)]).is_err());
    }

    #[test]
    fn roles_are_checked_and_older_files_read_without_them() {
        let wrong_unit = [ModelTarget::new("d", Unit::Deg).with_role(Role::Position)];
        let err = check_targets(&wrong_unit).unwrap_err().to_string();
        assert!(err.contains("in deg, not mm"), "{err}");
        let twice = [
            ModelTarget::new("a", Unit::Mm).with_role(Role::Position),
            ModelTarget::new("b", Unit::Mm).with_role(Role::Position),
        ];
        let err = check_targets(&twice).unwrap_err().to_string();
        assert!(err.contains("`a` and `b`"), "{err}");
        let old: ModelTarget =
            serde_json::from_str(r#"{"name": "r", "unit": "mm", "circular": false}"#).unwrap();
        assert_eq!(old.role, None);
        let marked = ModelTarget::circular("t").with_role(Role::Angle);
        let text = serde_json::to_string(&marked).unwrap();
        assert!(text.contains(r#""role":"angle""#), "{text}");
        assert_eq!(serde_json::from_str::<ModelTarget>(&text).unwrap(), marked);
        let plain = serde_json::to_string(&ModelTarget::new("r", Unit::Mm)).unwrap();
        assert!(!plain.contains("role"), "{plain}");
    }
}
