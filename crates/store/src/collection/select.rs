//! Which rows of a labels file a collection takes: the first `limit`
//! rows, and of those the frames whose number satisfies a [`KeepRule`]
//! (`N%5==0`: the score part of a split by frame number).
use super::CollectionError;
use serde::{Deserialize, Serialize};

/// The rows a collection takes from its labels file.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RowSelection {
    /// Only the first `limit` data rows of the file (all when `None`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub limit: Option<usize>,
    /// Of those, only the frames whose number this rule keeps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub keep: Option<KeepRule>,
}

/// `N % modulus == remainder` on a frame's number N (the first number in
/// its image name); made only by [`KeepRule::new`] or [`KeepRule::parse`]
/// (or read from a file, which checks the same), so `0 <= remainder <
/// modulus`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "KeepFile", into = "KeepFile")]
pub struct KeepRule {
    modulus: u64,
    remainder: u64,
}

/// The file form of a [`KeepRule`], before its check.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeepFile {
    modulus: u64,
    remainder: u64,
}

impl TryFrom<KeepFile> for KeepRule {
    type Error = CollectionError;

    fn try_from(f: KeepFile) -> Result<Self, Self::Error> {
        KeepRule::new(f.modulus, f.remainder)
            .ok_or_else(|| bad_rule(&format!("N%{}=={}", f.modulus, f.remainder)))
    }
}

impl From<KeepRule> for KeepFile {
    fn from(k: KeepRule) -> Self {
        KeepFile {
            modulus: k.modulus,
            remainder: k.remainder,
        }
    }
}

fn bad_rule(text: &str) -> CollectionError {
    CollectionError::KeepRule {
        text: text.to_string(),
    }
}

impl KeepRule {
    /// `N % modulus == remainder`; `None` unless `remainder < modulus`.
    pub fn new(modulus: u64, remainder: u64) -> Option<Self> {
        (remainder < modulus).then_some(Self { modulus, remainder })
    }

    /// Parse `N%M==K` (spaces allowed).
    pub fn parse(text: &str) -> Result<Self, CollectionError> {
        let plain: String = text.chars().filter(|c| !c.is_whitespace()).collect();
        let (m, k) = plain
            .strip_prefix("N%")
            .and_then(|rest| rest.split_once("=="))
            .ok_or_else(|| bad_rule(text))?;
        match (m.parse(), k.parse()) {
            (Ok(m), Ok(k)) => Self::new(m, k).ok_or_else(|| bad_rule(text)),
            _ => Err(bad_rule(text)),
        }
    }

    /// M of `N%M==K`.
    pub fn modulus(&self) -> u64 {
        self.modulus
    }

    /// K of `N%M==K`.
    pub fn remainder(&self) -> u64 {
        self.remainder
    }

    /// Whether the frame named `image` is kept (a name without a number is not).
    pub fn keeps(&self, image: &str) -> bool {
        frame_number(image).is_some_and(|n| n % self.modulus == self.remainder)
    }
}

impl std::fmt::Display for KeepRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "N%{}=={}", self.modulus, self.remainder)
    }
}

/// The first run of digits in a frame's name (`frame_17_0.png` -> 17).
pub fn frame_number(image: &str) -> Option<u64> {
    let start = image.find(|c: char| c.is_ascii_digit())?;
    let digits: String = image[start..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keep_rules_parse_and_select_by_frame_number() {
        let k = KeepRule::parse(" N % 5 == 1").unwrap();
        assert!(k.keeps("frame_11_0.png") && !k.keeps("frame_10_0.png"));
        assert!(!k.keeps("init.png"));
        for bad in ["N%0==0", "N%5==5", "M%5==0", "N%5=1", ""] {
            assert!(KeepRule::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(frame_number("frame_3762_0.png"), Some(3762));
    }

    #[test]
    fn a_keep_rule_read_from_a_file_is_checked() {
        let ok: KeepRule = toml::from_str("modulus = 5\nremainder = 0\n").unwrap();
        assert_eq!(ok.to_string(), "N%5==0");
        // A zero modulus once divided by zero on the first frame.
        assert!(toml::from_str::<KeepRule>("modulus = 0\nremainder = 0\n").is_err());
        assert!(toml::from_str::<KeepRule>("modulus = 5\nremainder = 5\n").is_err());
    }
}
