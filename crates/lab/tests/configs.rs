//! The controllers the lab runs by default: `follow` the tuned one,
//! `reproduce` the report's, and the shipped configs/follow-report.toml
//! gives the report's back (issue 12).
use std::path::Path;
use tactrace_control::PbtsConfig;
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::reproduce::ReproduceConfig;
use tactrace_store::load_config;

#[test]
fn follow_runs_the_tuned_controller_and_reproduce_the_reports() {
    assert_eq!(SimFollowConfig::default().controller, PbtsConfig::tuned());
    assert_eq!(
        ReproduceConfig::default().follow.controller,
        PbtsConfig::report()
    );
    assert!(PbtsConfig::report().policy.is_off());
    PbtsConfig::tuned().validate().unwrap();
    assert!(!PbtsConfig::tuned().policy.is_off());
}

#[test]
fn the_shipped_report_config_restores_the_reports_controller() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/follow-report.toml");
    let cfg: SimFollowConfig = load_config(Some(&path), "follow configuration").unwrap();
    assert_eq!(cfg.controller, PbtsConfig::report());
    let rest = SimFollowConfig::report();
    assert_eq!(
        toml::to_string(&cfg).unwrap(),
        toml::to_string(&rest).unwrap()
    );
}
