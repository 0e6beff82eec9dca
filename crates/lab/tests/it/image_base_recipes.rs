//! The pin recipes of the 331-pin sets as the base of a residual image
//! model (`[base]`, docs/learning.md, "The residual on a pin model"): the
//! surface's five-member PCADenNN at 400 epochs and the edge's turned
//! copies averaged over their views reach the base's configuration
//! (docs/results.md, "The 331-pin sets as a residual on their pin
//! models"); an ensemble base's fit: `image_base`'s own tests.
use tactrace_lab::image_base::{split_base_table, BaseSettings};
use tactrace_learn::ModelKind;

/// The `[base]` table of the configuration text `text`.
fn base_of(text: &str) -> BaseSettings {
    split_base_table(text)
        .expect("a configuration")
        .1
        .expect("a [base] table")
}

#[test]
fn the_surface_recipe_an_ensemble_at_400_epochs_reaches_the_base() {
    let base = base_of(
        "input = \"pin_model_and_pixels\"\n[base]\nmodel = \"pcadennn\"\n\
         [base.settings]\nepochs = 400\nensemble = 5\n",
    );
    assert_eq!(base.kind().unwrap(), ModelKind::PcaDenNN);
    let cfg = base.config().unwrap();
    assert_eq!((cfg.epochs, cfg.ensemble), (400, 5));
    assert!(cfg.rotations.is_none());
}

#[test]
fn the_edge_recipe_turned_copies_with_their_views_reaches_the_base() {
    let base = base_of(
        "input = \"pin_model_and_pixels\"\n[base]\nmodel = \"pcadennn\"\nfolds = 3\n\
         [base.settings]\nepochs = 30\n\
         [base.settings.pose]\nn_components = 35\nhidden = [512, 256]\n\
         [base.settings.rotations]\norder = 6\nangle_sign = -1\nat_prediction = true\n",
    );
    assert_eq!(base.folds, 3);
    let cfg = base.config().unwrap();
    let turns = cfg.rotations.expect("the turned copies");
    assert_eq!((turns.order, turns.angle_sign), (6, -1));
    assert!(turns.at_prediction);
    assert_eq!(cfg.epochs, 30);
    assert_eq!(cfg.pose.expect("the [pose] net").hidden, vec![512, 256]);
    // A bad turn is refused when the base is read, before any fit.
    let bad = base_of("[base]\n[base.settings.rotations]\norder = 1\nangle_sign = -1\n");
    assert!(bad.config().is_err());
}
