//! Seeds and integers past what TOML holds (signed 64-bit): a run whose
//! seed could not be written into its resolved `config.toml` is refused
//! before any work, naming the key or flag.
use crate::util;
use util::{collect, expect_code, expect_refusal_saying, train, TempDir};

#[test]
fn a_config_integer_past_i64_is_refused_naming_the_key() {
    let t = TempDir::new("seed-range-config");
    expect_code(&collect(&t.0, "40", &["--seed", "3"], "ds"), 0, "collect");
    std::fs::write(
        t.join("big.toml"),
        "epochs = 1\nseed = 18446744073709551615\n",
    )
    .unwrap();
    let r = train(&t.0, "pdennn", "ds", "1", "m", &["--config", "big.toml"]);
    expect_refusal_saying(&r, 2, "a seed past i64", &["`seed`", "line 2", "big.toml"]);
    assert!(!t.join("m").exists(), "nothing written");
    // The largest seed a TOML file holds trains, and the model records it.
    std::fs::write(t.join("max.toml"), "seed = 9223372036854775807\n").unwrap();
    let r = train(&t.0, "pdennn", "ds", "1", "m", &["--config", "max.toml"]);
    expect_code(&r, 0, "the largest seed");
    let model = std::fs::read_to_string(t.join("m").join("model.json")).unwrap();
    assert!(
        model.contains("\"seed\": 9223372036854775807"),
        "the seed recorded"
    );
}

#[test]
fn an_image_models_seed_flag_is_range_checked() {
    let t = TempDir::new("seed-range-flag");
    let past = (tactrace_learn::MAX_SEED + 1).to_string();
    let r = train(&t.0, "conv-dennn", "ds", "1", "m", &["--seed", &past]);
    expect_refusal_saying(&r, 2, "--seed past MAX_SEED", &["--seed", &past]);
}
