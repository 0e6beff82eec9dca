//! The TOML examples in docs/hardware.md parse into the real config types,
//! so the guide cannot drift from the code.
use tactrace_hw::{CommandSource, CommandSourceConfig, Ur5Config};

fn toml_blocks(markdown: &str) -> Vec<String> {
    markdown
        .split("```toml\n")
        .skip(1)
        .filter_map(|rest| rest.split("```").next().map(str::to_string))
        .collect()
}

#[test]
fn hardware_guide_examples_parse() {
    let blocks = toml_blocks(include_str!("../../../docs/hardware.md"));
    // The arm and the camera examples come first; the rig file of
    // `follow --hardware` after them is checked by the lab crate's tests.
    assert!(
        blocks.len() >= 2,
        "expected the arm and the camera examples"
    );
    let arm: Ur5Config = toml::from_str(&blocks[0]).expect("Ur5Config example parses");
    arm.validate().expect("Ur5Config example is valid");
    assert_eq!(arm.tcp.rx, 180.0);
    let camera: CommandSourceConfig = toml::from_str(&blocks[1]).expect("camera example parses");
    assert!(CommandSource::from_config(&camera).is_ok());
    assert!(camera.args.iter().any(|a| a == "{output}"));
}

#[test]
fn command_source_config_is_checked() {
    let bad: CommandSourceConfig =
        toml::from_str("program = \"\"\noutput = \"/tmp/x.png\"").expect("parses");
    assert!(CommandSource::from_config(&bad).is_err());
    let unknown = toml::from_str::<CommandSourceConfig>("program = \"a\"\noutput = \"b\"\ncmd = 1");
    assert!(unknown.is_err());
}
