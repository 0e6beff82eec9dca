//! The TOML examples in docs/hardware.md parse into the real config types,
//! so the guide cannot drift from the code.
use tactrace_hw::{CommandSource, CommandSourceConfig, Ur5Config, V4l2Config};

fn toml_blocks(markdown: &str) -> Vec<String> {
    markdown
        .split("```toml\n")
        .skip(1)
        .filter_map(|rest| rest.split("```").next().map(str::to_string))
        .collect()
}

#[test]
fn hardware_guide_examples_parse() {
    let blocks = toml_blocks(include_str!("../../../../docs/hardware.md"));
    // The arm, the V4L2 camera and the command camera examples come first; the rig file of
    // `follow --hardware` after them is checked by the lab crate's tests.
    assert!(
        blocks.len() >= 3,
        "expected the arm and the camera examples"
    );
    let arm: Ur5Config = toml::from_str(&blocks[0]).expect("Ur5Config example parses");
    arm.validate().expect("Ur5Config example is valid");
    assert_eq!(arm.tcp.rx, 180.0);
    #[derive(serde::Deserialize)]
    struct V4l2Table {
        camera: std::collections::BTreeMap<String, V4l2Config>,
    }
    let v4l2: V4l2Table = toml::from_str(&blocks[1]).expect("[camera.v4l2] example parses");
    let v4l2 = &v4l2.camera["v4l2"];
    v4l2.validate().expect("V4l2Config example is valid");
    assert_eq!(
        (v4l2.width, v4l2.height, v4l2.exposure),
        (640, 480, Some(156))
    );
    let camera: CommandSourceConfig = toml::from_str(&blocks[2]).expect("camera example parses");
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
