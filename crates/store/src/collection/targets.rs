//! What a collection's labels are: the column naming each row's frame and
//! the target columns, each with its unit and whether it is circular (an
//! angle over the full circle, whose errors wrap). Checked when made: a
//! spec names at least one target and no column twice.
use super::CollectionError;
use serde::{Deserialize, Serialize};

/// The unit of a target column (millimetres and degrees at every public
/// boundary): the models' own, so a spec and a model name units alike.
pub use tactrace_learn::{Role, Unit};

/// One target: a label column, its unit, whether it is circular, and its
/// role in an edge task when marked (needed only beside other targets).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    /// The column's name in the labels file's header.
    pub column: String,
    pub unit: Unit,
    /// An angle over the full circle (its errors wrap at +-180 deg).
    #[serde(default)]
    pub circular: bool,
    /// The edge pose's position or angle, when marked.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub role: Option<Role>,
}

impl Target {
    /// A target column in `unit`, not circular, no role marked.
    pub fn new(column: impl Into<String>, unit: Unit) -> Self {
        Self {
            column: column.into(),
            unit,
            circular: false,
            role: None,
        }
    }

    /// A target as the CLI writes it: `COLUMN:UNIT[:circular][:ROLE]`,
    /// unit `mm` or `deg`, role `position` or `angle` (e.g.
    /// `pose_6:deg:circular`, `pose_2:mm:position`).
    pub fn parse(text: &str) -> Result<Self, CollectionError> {
        let bad = || CollectionError::TargetText {
            text: text.to_string(),
        };
        let parts: Vec<&str> = text.split(':').map(str::trim).collect();
        let [column, unit, marks @ ..] = parts.as_slice() else {
            return Err(bad());
        };
        let unit = match *unit {
            "mm" => Unit::Mm,
            "deg" => Unit::Deg,
            _ => return Err(bad()),
        };
        let (circular, role) = match marks {
            [] => (false, None),
            ["circular"] => (true, None),
            ["circular", r] => (true, Some(Role::parse(r).ok_or_else(bad)?)),
            [r] => (false, Some(Role::parse(r).ok_or_else(bad)?)),
            _ => return Err(bad()),
        };
        Ok(Self {
            column: column.to_string(),
            unit,
            circular,
            role,
        })
    }

    /// The target as a model names it.
    pub fn model_target(&self) -> tactrace_learn::ModelTarget {
        tactrace_learn::ModelTarget {
            name: self.column.clone(),
            unit: self.unit,
            circular: self.circular,
            role: self.role,
        }
    }

    /// `COLUMN:UNIT[:circular][:ROLE]`, as [`Target::parse`] reads it.
    pub fn text(&self) -> String {
        let circular = if self.circular { ":circular" } else { "" };
        let role = self
            .role
            .map_or(String::new(), |r| format!(":{}", r.as_str()));
        format!("{}:{}{circular}{role}", self.column, self.unit.as_str())
    }
}

/// The label columns of a collection: the image-name column and the
/// targets, in order. Made only through [`TargetSpec::new`] (or read from
/// a file, which checks the same), so a spec in hand names at least one
/// target and every column once.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "SpecFile", into = "SpecFile")]
pub struct TargetSpec {
    image_column: String,
    targets: Vec<Target>,
}

/// The file form of a [`TargetSpec`], before its checks.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecFile {
    image_column: String,
    targets: Vec<Target>,
}

impl TryFrom<SpecFile> for TargetSpec {
    type Error = CollectionError;

    fn try_from(f: SpecFile) -> Result<Self, Self::Error> {
        TargetSpec::new(f.image_column, f.targets)
    }
}

impl From<TargetSpec> for SpecFile {
    fn from(s: TargetSpec) -> Self {
        SpecFile {
            image_column: s.image_column,
            targets: s.targets,
        }
    }
}

impl TargetSpec {
    /// The image-name column and the targets; refused when there is no
    /// target, a name is empty, or a column is named twice (the image
    /// column included).
    pub fn new(
        image_column: impl Into<String>,
        targets: Vec<Target>,
    ) -> Result<Self, CollectionError> {
        let image_column = image_column.into();
        if targets.is_empty() {
            return Err(CollectionError::NoTargets);
        }
        let names: Vec<&str> = std::iter::once(image_column.as_str())
            .chain(targets.iter().map(|t| t.column.as_str()))
            .collect();
        for (k, name) in names.iter().enumerate() {
            if name.trim().is_empty() {
                return Err(CollectionError::EmptyColumn);
            }
            if names[..k].contains(name) {
                return Err(CollectionError::ColumnTwice {
                    column: name.to_string(),
                });
            }
        }
        if let Some(t) = targets.iter().find(|t| t.circular && t.unit != Unit::Deg) {
            return Err(CollectionError::CircularNotDegrees {
                column: t.column.clone(),
            });
        }
        let model: Vec<_> = targets.iter().map(Target::model_target).collect();
        tactrace_learn::check_targets(&model).map_err(|e| CollectionError::Roles {
            reason: e.to_string(),
        })?;
        Ok(Self {
            image_column,
            targets,
        })
    }

    /// An edge task's two targets: the edge position `r` (mm) and the
    /// edge angle `theta` (deg, not circular), images named in `image`.
    pub fn edge(image: &str, r: &str, theta: &str) -> Result<Self, CollectionError> {
        Self::new(
            image,
            vec![Target::new(r, Unit::Mm), Target::new(theta, Unit::Deg)],
        )
    }

    /// The column naming each row's frame file.
    pub fn image_column(&self) -> &str {
        &self.image_column
    }

    /// The targets, in order.
    pub fn targets(&self) -> &[Target] {
        &self.targets
    }

    /// The targets as a model names them, in order.
    pub fn model_targets(&self) -> Vec<tactrace_learn::ModelTarget> {
        self.targets.iter().map(Target::model_target).collect()
    }

    /// The columns of an edge task's two targets, position (mm) then
    /// angle (deg): the commands that replay or simulate an edge (`twin`,
    /// `calibrate`, `follow --replay`) refuse any other spec; `import` and
    /// the models take any.
    pub fn edge_columns(&self) -> Result<[&str; 2], CollectionError> {
        match self.targets.as_slice() {
            [r, theta] if r.unit == Unit::Mm && theta.unit == Unit::Deg => {
                Ok([r.column.as_str(), theta.column.as_str()])
            }
            _ => Err(CollectionError::NotAnEdgeTask {
                targets: self
                    .targets
                    .iter()
                    .map(|t| format!("{} ({})", t.column, t.unit.as_str()))
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
        }
    }

    /// A dataset's target names for the edge task's columns
    /// (`r_mm (pose_2)`, `theta_deg (pose_6)`).
    pub fn edge_names(&self) -> Result<[String; 2], CollectionError> {
        let [r, theta] = self.edge_columns()?;
        Ok([format!("r_mm ({r})"), format!("theta_deg ({theta})")])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spec_names_a_target_and_every_column_once() {
        assert!(matches!(
            TargetSpec::new("image_name", vec![]),
            Err(CollectionError::NoTargets)
        ));
        let twice = TargetSpec::edge("image_name", "pose_2", "pose_2").unwrap_err();
        assert!(twice.to_string().contains("`pose_2`"), "{twice}");
        assert!(TargetSpec::edge("pose_2", "pose_2", "pose_6").is_err());
        assert!(TargetSpec::edge("image_name", " ", "pose_6").is_err());
        // Read from a file, the same checks.
        let text = "image_column = \"image_name\"\ntargets = []\n";
        assert!(toml::from_str::<TargetSpec>(text).is_err());
    }

    #[test]
    fn targets_parse_as_the_cli_writes_them() {
        let t = Target::parse("pose_6:deg:circular").unwrap();
        assert_eq!(
            (t.column.as_str(), t.unit, t.circular),
            ("pose_6", Unit::Deg, true)
        );
        assert_eq!(t.text(), "pose_6:deg:circular");
        assert_eq!(
            Target::parse("pose_2:mm").unwrap(),
            Target::new("pose_2", Unit::Mm)
        );
        let marked = Target::parse("pose_6:deg:circular:angle").unwrap();
        assert_eq!((marked.circular, marked.role), (true, Some(Role::Angle)));
        assert_eq!(marked.text(), "pose_6:deg:circular:angle");
        let position = Target::parse("pose_2:mm:position").unwrap();
        assert_eq!(
            (position.circular, position.role),
            (false, Some(Role::Position))
        );
        assert_eq!(Target::parse(&position.text()).unwrap(), position);
        for bad in [
            "pose_2",
            "pose_2:cm",
            "pose_2:mm:round",
            "a:mm:circular:x",
            "a:deg:angle:circular",
            "a:deg:circular:angle:angle",
        ] {
            let err = Target::parse(bad).unwrap_err().to_string();
            assert!(err.contains(bad), "{err}");
        }
        // A role on a target of the wrong unit, or marked twice, is refused.
        let err = TargetSpec::new("image", vec![Target::parse("d:deg:position").unwrap()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("`d`") && err.contains("position"), "{err}");
        let twice = ["a:mm:position", "b:mm:position"].map(|t| Target::parse(t).unwrap());
        assert!(TargetSpec::new("image", twice.to_vec()).is_err());
        // Only an angle wraps.
        let err = TargetSpec::new("image", vec![Target::parse("d:mm:circular").unwrap()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("`d`"), "{err}");
    }

    #[test]
    fn a_spec_of_n_targets_round_trips_and_only_the_edge_pair_makes_a_dataset() {
        let mut angle = Target::new("pose_6", Unit::Deg);
        angle.circular = true;
        let spec = TargetSpec::new(
            "image_name",
            vec![
                Target::new("pose_3", Unit::Mm),
                Target::new("pose_4", Unit::Deg),
                angle,
            ],
        )
        .unwrap();
        let text = toml::to_string(&spec).unwrap();
        assert!(text.contains("circular = true"), "{text}");
        assert_eq!(toml::from_str::<TargetSpec>(&text).unwrap(), spec);
        let err = spec.edge_columns().unwrap_err().to_string();
        assert!(
            err.contains("pose_3 (mm), pose_4 (deg), pose_6 (deg)"),
            "{err}"
        );
        let edge = TargetSpec::edge("image_name", "pose_2", "pose_6").unwrap();
        assert_eq!(edge.edge_columns().unwrap(), ["pose_2", "pose_6"]);
        assert_eq!(
            edge.edge_names().unwrap(),
            [
                "r_mm (pose_2)".to_string(),
                "theta_deg (pose_6)".to_string()
            ]
        );
    }
}
