//! The SE(3) controller's bounded move and held heading (issue 23, the
//! full-range edge and heading control on surfaces): `move_clip` bounds
//! each component of the move, `heading_deg` turns a surface run onto a
//! direction of travel read from the commanded pose.
use tactrace_arm::Pose;
use tactrace_control::{
    heading_error_deg, ControlError, Se3Config, Se3Controller, Task, EDGE_MOVE_CLIP,
};
use tactrace_shape3d::{HeightField, Object3d, Vec3};

/// edge_5d with the rz move bounded to +-`rz` deg.
fn clipped_edge(rz: f64) -> Se3Config {
    Se3Config {
        move_clip: Some([5.0, 5.0, 5.0, 45.0, 45.0, rz]),
        ..Se3Config::edge_5d()
    }
}

/// edge_5d without a bound on the move (the preset before the bound).
fn free_edge() -> Se3Config {
    Se3Config {
        move_clip: None,
        ..Se3Config::edge_5d()
    }
}

#[test]
fn move_clip_bounds_a_misread_rotation() {
    // A tap read nearly half a turn away: the unbounded law turns by 85 deg.
    let misread = [0.0, 0.0, 3.0, 0.0, 0.0, 170.0];
    let mut free = Se3Controller::try_new(free_edge()).unwrap();
    let u = free.step(misread).unwrap();
    assert!(u[5].abs() > 80.0, "{u:?}");
    let mut c = Se3Controller::try_new(clipped_edge(20.0)).unwrap();
    let v = c.step(misread).unwrap();
    assert!((v[5].abs() - 20.0).abs() < 1e-12, "{v:?}");
    assert_eq!(v[5].signum(), u[5].signum());
    // The other components are the unbounded law's.
    for k in 0..5 {
        assert!((u[k] - v[k]).abs() < 1e-12, "{k}: {u:?} {v:?}");
    }
    // The integral still sums the error (the clip is on the move only).
    assert_eq!(free.integral(), c.integral());
}

#[test]
fn move_clip_leaves_moves_within_it_alone() {
    let predictions = [
        [0.4, 0.0, 2.7, 3.0, -2.0, 6.0],
        [-0.2, 0.0, 3.3, -1.0, 4.0, -9.0],
        [0.1, 0.0, 3.0, 0.5, 0.5, 2.0],
    ];
    let mut free = Se3Controller::try_new(free_edge()).unwrap();
    let mut c = Se3Controller::try_new(clipped_edge(20.0)).unwrap();
    for p in predictions {
        assert_eq!(free.step(p).unwrap(), c.step(p).unwrap());
    }
}

#[test]
fn move_clip_and_heading_are_checked_and_read_from_toml() {
    let text = r#"
task = "surface_3d"
reference = [0.0, 1.0, 3.0, 0.0, 0.0, 0.0]
kp = [1.0, 1.0, 0.5, 0.5, 0.5, 0.5]
ki = [0.0, 0.0, 0.3, 0.1, 0.1, 0.0]
integral_clip = [5.0, 5.0, 5.0, 45.0, 45.0, 45.0]
move_clip = [5.0, 5.0, 5.0, 30.0, 30.0, 10.0]
heading_deg = 30.0
"#;
    let c: Se3Config = toml::from_str(text).unwrap();
    assert_eq!(c.heading_deg, Some(30.0));
    assert_eq!(c.move_clip.unwrap()[5], 10.0);
    // Round trip through the run folder's config.toml.
    let back: Se3Config = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
    assert_eq!(back, c);
    // The edge presets bound the turn to 20 deg a step; surface_3d holds
    // no heading; configs without the keys still read (see the TOML above
    // without them: neither set).
    assert_eq!(Se3Config::edge_5d().move_clip, Some(EDGE_MOVE_CLIP));
    assert_eq!(Se3Config::edge_3d().move_clip.unwrap()[5], 20.0);
    assert_eq!(Se3Config::surface_3d().move_clip, None);
    assert_eq!(Se3Config::surface_3d().heading_deg, None);
    let old = text
        .lines()
        .filter(|l| !l.starts_with("move_clip") && !l.starts_with("heading_deg"))
        .collect::<Vec<_>>()
        .join("\n");
    let old: Se3Config = toml::from_str(&old).unwrap();
    assert_eq!((old.move_clip, old.heading_deg), (None, None));
    let negative = Se3Config {
        move_clip: Some([1.0, 1.0, 1.0, 1.0, 1.0, -1.0]),
        ..Se3Config::edge_5d()
    };
    assert!(matches!(
        negative.validate(),
        Err(ControlError::NegativeClip {
            field: "move_clip",
            index: 5,
            ..
        })
    ));
    let nan = Se3Config {
        heading_deg: Some(f64::NAN),
        ..Se3Config::surface_3d()
    };
    assert!(matches!(
        nan.validate(),
        Err(ControlError::NonFinite {
            field: "heading_deg",
            ..
        })
    ));
    // A task that senses rz turns by its prediction, not by a heading.
    for task in [Task::Edge2d, Task::Edge3d, Task::Edge5d] {
        let c = Se3Config {
            heading_deg: Some(0.0),
            ..Se3Config::for_task(task)
        };
        assert!(c.validate().is_err(), "{task}");
    }
}

#[test]
fn heading_error_is_the_turn_about_the_axis_onto_the_direction() {
    // Level, the y axis along +x (rz = -90): heading 0 is held.
    let level = Pose::new(0.0, 0.0, 0.0, 0.0, 0.0, -90.0);
    assert!(heading_error_deg(level, 0.0).abs() < 1e-9);
    assert!((heading_error_deg(level, 30.0) - 30.0).abs() < 1e-9);
    assert!((heading_error_deg(level, -135.0) + 135.0).abs() < 1e-9);
    // Turning by the error about the sensor's axis holds the direction.
    for pose in [
        Pose::new(1.0, 2.0, 3.0, 20.0, -10.0, 40.0),
        Pose::new(0.0, 0.0, 0.0, -25.0, 15.0, -120.0),
    ] {
        let e = heading_error_deg(pose, 75.0);
        let turned = tactrace_control::apply_servo(pose, [0.0, 0.0, 0.0, 0.0, 0.0, e]);
        assert!(heading_error_deg(turned, 75.0).abs() < 1e-9, "{pose:?}");
        // The turned y axis lies in the vertical plane of the direction,
        // pointing along it.
        let y = turned.to_isometry().rotation * Vec3::y();
        let d = Vec3::new(75f64.to_radians().cos(), 75f64.to_radians().sin(), 0.0);
        assert!(y.dot(&Vec3::z().cross(&d)).abs() < 1e-9 && y.dot(&d) > 0.0);
    }
    // A level axis across the direction: no line of the sensor's plane
    // runs over it, 0.
    let side = Pose::new(0.0, 0.0, 0.0, 90.0, 0.0, 0.0);
    assert_eq!(heading_error_deg(side, 0.0), 0.0);
}

/// The sensor's pose against the nearest surface point (z as depth), from
/// the geometry: a pose oracle standing in for a model.
fn oracle(surface: &dyn Object3d, pose: Pose) -> [f64; 6] {
    let sensor = pose.to_isometry();
    let p = sensor.translation.vector;
    let axis = sensor.rotation * Vec3::z();
    let tilt = nalgebra::UnitQuaternion::rotation_between(&axis, &surface.normal(p)).unwrap();
    let frame =
        nalgebra::Isometry3::from_parts(surface.closest_point(p).into(), tilt * sensor.rotation);
    let s = Pose::from_isometry(&(frame.inverse() * sensor));
    [s.x, s.y, -s.z, s.rx, s.ry, s.rz]
}

/// The direction of travel (deg from +x) of the last `n` steps and the
/// worst heading error over them, surface_3d from a level start heading
/// along +x over `surface`, holding `heading`.
fn steer(surface: &dyn Object3d, heading: Option<f64>, steps: usize, n: usize) -> (f64, f64) {
    let cfg = Se3Config {
        heading_deg: heading,
        kp: [1.0, 1.0, 0.5, 0.5, 0.5, 0.5],
        ..Se3Config::surface_3d()
    };
    let mut c = Se3Controller::try_new(cfg).unwrap();
    let start = surface.closest_point(Vec3::new(-30.0, 10.0, 50.0));
    let mut pose = Pose::new(start.x, start.y, start.z - 3.0, 0.0, 0.0, -90.0);
    let mut path = vec![pose];
    for _ in 0..steps {
        pose = c.next_pose(pose, oracle(surface, pose)).unwrap();
        path.push(pose);
    }
    let last = &path[path.len() - n..];
    let (a, b) = (last[0], last[n - 1]);
    let direction = (b.y - a.y).atan2(b.x - a.x).to_degrees();
    let worst = last
        .iter()
        .map(|p| heading_error_deg(*p, heading.unwrap_or(0.0)).abs())
        .fold(0.0, f64::max);
    (direction, worst)
}

#[test]
fn a_held_heading_turns_a_surface_run_onto_its_direction() {
    let saddle = HeightField::saddle(60.0).unwrap();
    let wave = HeightField::wave(4.0, 60.0, 0.0).unwrap();
    for (name, surface) in [("saddle", &saddle as &dyn Object3d), ("wave", &wave)] {
        // Started along +x, steered to 40 deg: turned within a few steps,
        // then the path runs along 40 deg, its heading held to 0.5 deg.
        let (direction, worst) = steer(surface, Some(40.0), 40, 25);
        eprintln!("{name}: direction {direction:.2} deg, worst heading error {worst:.3} deg");
        assert!((direction - 40.0).abs() < 2.0, "{name}: {direction}");
        assert!(worst < 0.5, "{name}: {worst}");
        // Without a heading the run keeps going along +x.
        let (direction, _) = steer(surface, None, 40, 25);
        assert!(direction.abs() < 5.0, "{name}: {direction}");
    }
}
