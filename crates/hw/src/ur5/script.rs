//! Pure conversions between tactrace poses and the UR controller's pose form.
//!
//! tactrace poses are millimetres and degrees, orientation as extrinsic
//! rotations about fixed x, y, z (the cri/Bristol `sxyz` convention, so
//! R = Rz(rz) Ry(ry) Rx(rx)). The UR controller speaks metres and an
//! axis-angle rotation vector in radians, `p[x, y, z, rx, ry, rz]`, both in
//! its base frame. The work frame (base -> work transform, as the Bristol
//! code's `work_frame`) is applied here: a work-frame pose `P` is sent as
//! the base-frame pose `W * P` (the same frame change the report uses in
//! eq. 5.7-5.8 for moves in the sensor frame).
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use tactrace_geometry::Pose;

use super::state::ToolPose;
use crate::HwError;

/// A pose as the UR "tool vector" [x, y, z (m), rx, ry, rz (rotation
/// vector, rad)]: mm -> m, Euler degrees -> `UnitQuaternion::scaled_axis`.
pub fn pose_to_tool_vector(pose: Pose) -> [f64; 6] {
    isometry_to_tool_vector(&pose.to_isometry())
}

/// Inverse of [`pose_to_tool_vector`].
pub fn tool_vector_to_pose(v: [f64; 6]) -> Pose {
    Pose::from_isometry(&tool_vector_to_isometry(v))
}

/// A rigid transform (mm) as a UR tool vector (m, rotation vector rad).
pub fn isometry_to_tool_vector(iso: &Isometry3<f64>) -> [f64; 6] {
    let t = iso.translation.vector / 1000.0;
    let r = iso.rotation.scaled_axis();
    [t.x, t.y, t.z, r.x, r.y, r.z]
}

/// A UR tool vector (m, rotation vector rad) as a rigid transform in mm.
pub fn tool_vector_to_isometry(v: [f64; 6]) -> Isometry3<f64> {
    let rotation = UnitQuaternion::from_scaled_axis(Vector3::new(v[3], v[4], v[5]));
    let t = Translation3::new(v[0] * 1000.0, v[1] * 1000.0, v[2] * 1000.0);
    Isometry3::from_parts(t, rotation)
}

/// The base-frame transform of a work-frame pose: `work_frame * pose`.
pub fn work_to_base(work_frame: Pose, pose: Pose) -> Isometry3<f64> {
    work_frame.to_isometry() * pose.to_isometry()
}

/// The work-frame pose of a base-frame transform: `work_frame^-1 * base`.
pub fn base_to_work(work_frame: Pose, base: &Isometry3<f64>) -> Pose {
    Pose::from_isometry(&(work_frame.to_isometry().inverse() * base))
}

/// Fails on the first NaN or infinite component of `pose`.
pub fn check_finite(pose: Pose) -> Result<(), HwError> {
    const NAMES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
    match NAMES
        .iter()
        .zip(pose.to_array())
        .find(|(_, v)| !v.is_finite())
    {
        Some((name, _)) => Err(HwError::PoseNotFinite { component: name }),
        None => Ok(()),
    }
}

/// A tool vector written as a URScript pose literal `p[x, y, z, rx, ry, rz]`
/// (metres to the micrometre, radians to 1e-7).
pub fn format_script_pose(v: [f64; 6]) -> String {
    format!(
        "p[{:.6}, {:.6}, {:.6}, {:.7}, {:.7}, {:.7}]",
        v[0], v[1], v[2], v[3], v[4], v[5]
    )
}

/// A pose (mm, deg; frame of the caller's choosing) as a URScript pose
/// literal in metres and rotation-vector radians.
pub fn pose_to_script(pose: Pose) -> String {
    format_script_pose(pose_to_tool_vector(pose))
}

/// Parses a URScript pose literal `p[x, y, z, rx, ry, rz]` (surrounding
/// blanks allowed) into a tool vector (m, rad).
pub fn parse_script_pose(text: &str) -> Result<[f64; 6], HwError> {
    let bad = |reason: &str| HwError::ScriptPose {
        text: text.to_string(),
        reason: reason.to_string(),
    };
    let inner = text
        .trim()
        .strip_prefix("p[")
        .and_then(|rest| rest.strip_suffix(']'))
        .ok_or_else(|| bad("expected p[...]"))?;
    let mut values = [0.0; 6];
    let mut count = 0;
    for field in inner.split(',') {
        let value: f64 = field.trim().parse().map_err(|_| bad("not a number"))?;
        if count == 6 {
            return Err(bad("more than six numbers"));
        }
        if !value.is_finite() {
            return Err(bad("not finite"));
        }
        values[count] = value;
        count += 1;
    }
    if count != 6 {
        return Err(bad("fewer than six numbers"));
    }
    Ok(values)
}

/// Parses a URScript pose literal into a pose in mm and degrees.
pub fn script_to_pose(text: &str) -> Result<Pose, HwError> {
    parse_script_pose(text).map(tool_vector_to_pose)
}

/// Position (mm) and rotation (deg) distance between two transforms.
pub fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let position = (a.translation.vector - b.translation.vector).norm();
    let rotation = a.rotation.angle_to(&b.rotation).to_degrees();
    (position, rotation)
}

/// A URScript program that sets the tool centre point and moves linearly.
///
/// The secondary interface runs a `def ... end` block as one program; the
/// TCP is set inside it so the move uses it whatever the installation says.
/// The target is a checked [`ToolPose`]: finite and within reach.
pub fn movel_program(target: &ToolPose, tcp: [f64; 6], accel_m_s2: f64, speed_m_s: f64) -> String {
    format!(
        "def tactrace_move():\n  set_tcp({})\n  movel({}, a={:.4}, v={:.4})\nend\n",
        format_script_pose(tcp),
        format_script_pose(target.values()),
        accel_m_s2,
        speed_m_s
    )
}

/// A URScript program that only sets the tool centre point.
pub fn set_tcp_program(tcp: [f64; 6]) -> String {
    format!(
        "def tactrace_tcp():\n  set_tcp({})\nend\n",
        format_script_pose(tcp)
    )
}

/// A URScript program that decelerates a linear move to a stop.
pub fn stopl_program(accel_m_s2: f64) -> String {
    format!("def tactrace_stop():\n  stopl({accel_m_s2:.4})\nend\n")
}

/// The target of the first `movel(p[...]` in a line of URScript, if any.
pub fn find_movel_target(line: &str) -> Option<[f64; 6]> {
    let start = line.find("movel(")? + "movel(".len();
    let rest = &line[start..];
    let end = rest.find(']')? + 1;
    parse_script_pose(&rest[..end]).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn quarter_turn_about_z_is_rotation_vector_pi_over_2() {
        let v = pose_to_tool_vector(Pose::new(100.0, -20.0, 5.0, 0.0, 0.0, 90.0));
        let expected = [0.1, -0.02, 0.005, 0.0, 0.0, FRAC_PI_2];
        for (got, want) in v.iter().zip(expected) {
            assert!(close(*got, want, 1e-12), "{v:?}");
        }
    }

    #[test]
    fn tool_flange_pointing_down_is_pi_about_x() {
        let v = pose_to_tool_vector(Pose::new(0.0, 0.0, 0.0, 180.0, 0.0, 0.0));
        assert!(close(v[3].abs(), std::f64::consts::PI, 1e-12), "{v:?}");
        assert!(close(v[4], 0.0, 1e-12) && close(v[5], 0.0, 1e-12));
    }

    #[test]
    fn euler_order_is_extrinsic_xyz() {
        // rx = 90 then rz = 90 about fixed axes maps the x axis to y
        // and the y axis to z.
        let iso = Pose::new(0.0, 0.0, 0.0, 90.0, 0.0, 90.0).to_isometry();
        let ex = iso.rotation * Vector3::x();
        let ey = iso.rotation * Vector3::y();
        assert!((ex - Vector3::y()).norm() < 1e-12, "{ex}");
        assert!((ey - Vector3::z()).norm() < 1e-12, "{ey}");
    }

    #[test]
    fn tool_vector_round_trip() {
        let pose = Pose::new(412.5, -33.0, 87.25, 12.0, -20.0, 135.0);
        let back = tool_vector_to_pose(pose_to_tool_vector(pose));
        for (a, b) in pose.to_array().iter().zip(back.to_array()) {
            assert!(close(*a, b, 1e-9), "{pose:?} vs {back:?}");
        }
    }

    #[test]
    fn script_string_round_trip_to_micrometre() {
        let pose = Pose::new(-288.0, 10.5, -100.0, 0.0, 180.0, -90.0);
        let text = pose_to_script(pose);
        assert!(
            text.starts_with("p[-0.288000, 0.010500, -0.100000,"),
            "{text}"
        );
        let back = script_to_pose(&text).unwrap().to_isometry();
        let (dp, dr) = pose_error(&pose.to_isometry(), &back);
        assert!(dp < 1e-3 && dr < 1e-4, "{dp} mm {dr} deg");
    }

    #[test]
    fn bad_script_poses_are_errors() {
        for text in [
            "[1,2,3,4,5,6]",
            "p[1,2,3]",
            "p[1,2,3,4,5,6,7]",
            "p[1,a,3,4,5,6]",
            "p[1,2,3,4,5,inf]",
        ] {
            assert!(parse_script_pose(text).is_err(), "{text}");
        }
    }

    #[test]
    fn work_frame_round_trip_and_bristol_frame() {
        let work = Pose::new(288.0, 0.0, -100.0, 0.0, 0.0, -90.0);
        let pose = Pose::new(3.0, -2.0, 1.0, 0.0, 0.0, 30.0);
        let base = work_to_base(work, pose);
        // work x axis is base -y: moving +3 mm in work x goes -3 mm in base y.
        assert!(close(base.translation.x, 288.0 - 2.0, 1e-9));
        assert!(close(base.translation.y, -3.0, 1e-9));
        let back = base_to_work(work, &base);
        for (a, b) in pose.to_array().iter().zip(back.to_array()) {
            assert!(close(*a, b, 1e-9), "{back:?}");
        }
    }

    #[test]
    fn movel_program_holds_a_parsable_target() {
        let target = pose_to_tool_vector(Pose::new(400.0, 0.0, 50.0, 180.0, 0.0, 0.0));
        let checked = ToolPose::new(target, "target").unwrap();
        let program = movel_program(&checked, [0.0, 0.0, 0.1, 0.0, 0.0, 0.0], 0.1, 0.01);
        assert!(program.starts_with("def tactrace_move():\n"));
        assert!(program.ends_with("end\n"));
        let line = program.lines().find(|l| l.contains("movel")).unwrap();
        let parsed = find_movel_target(line).unwrap();
        for (a, b) in target.iter().zip(parsed) {
            assert!(close(*a, b, 1e-6));
        }
        assert!(line.contains("a=0.1000, v=0.0100"), "{line}");
    }

    #[test]
    fn non_finite_pose_is_rejected() {
        let err = check_finite(Pose::new(0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0));
        assert!(matches!(
            err,
            Err(HwError::PoseNotFinite { component: "y" })
        ));
        assert!(check_finite(Pose::default()).is_ok());
    }
}
