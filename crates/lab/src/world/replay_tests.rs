//! The real-frame world reads a tap's frame as `import` reads the same
//! frame: the shared 331-pin edge set with a sensor file proposed by the
//! inspection (small-pin detector, dome mask) and its rest layout
//! estimated from the taps, bit-identical pin vectors.
use super::{load_bank, replay_reader, ReplayBank};
use crate::import_reader::{open, read_one};
use tactrace_store::collection::{CollectionEdits, Reference};
use tactrace_store::{LabelledCollection, TapFields};
use tactrace_vision::{inspect, preprocess::grey_of, DetectorParams, SightParams};

#[test]
fn the_real_frame_world_reads_a_331_pin_frame_as_import_does() {
    let Some(set) = tactrace_testdata::shared_set("tactip331-edge2d-shear", "val/targets.csv")
    else {
        return;
    };
    let val = set.join("val");
    let edits = CollectionEdits {
        image_column: Some("sensor_image".into()),
        limit: Some(120),
        ..CollectionEdits::default()
    };
    let frames: Vec<_> = (1..=20)
        .map(|k| {
            let path = val.join(format!("frames/image_{}.png", 37 * k));
            grey_of(&tactrace_sensor::read_image(&path).unwrap())
        })
        .collect();
    let found = inspect(&frames, None).unwrap();
    assert!(matches!(found.detect, DetectorParams::Spots(_)));
    let sight = SightParams {
        preprocess: found.preprocess,
        detect: found.detect,
    };
    let collection = LabelledCollection::bristol(&val)
        .edited(&edits)
        .unwrap()
        .with_sight(Some(sight))
        .with_reference(Reference::Estimate { pins: Some(331) });
    let rows = collection.read_rows(TapFields::NONE).unwrap();
    let paths: Vec<_> = rows
        .iter()
        .map(|r| val.join("frames").join(&r.image))
        .collect();
    let imported = open(&collection, &paths).unwrap();
    let resolved = collection.with_reference(imported.reference.clone());
    let bank = load_bank(&ReplayBank::new(resolved.clone(), 0.5).unwrap()).unwrap();
    let (world, _) = replay_reader(&resolved, &bank).unwrap();
    assert_eq!(world.tracker().reference().len(), 331);
    assert_eq!(
        world.tracker().reference(),
        imported.reader.tracker().reference()
    );
    let mut read = 0;
    for path in paths.iter().step_by(4) {
        let Ok((want, _)) = read_one(&imported.reader, path) else {
            continue; // a frame import rejects (too few pins)
        };
        // What the world's sensor hands the perception, and how it reads it.
        let frame = tactrace_sensor::read_frame(path).unwrap();
        let got = world.read_grey(&frame).unwrap();
        assert_eq!(
            got.displacement(world.tracker().reference()),
            want,
            "{}",
            path.display()
        );
        read += 1;
    }
    assert!(read >= 25, "{read} frames compared");
}
