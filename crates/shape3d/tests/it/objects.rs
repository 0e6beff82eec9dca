//! Theory tests of the 3D objects (issue 23, item 1): signed distances on
//! points whose answer is known, normals equal to the distance's
//! gradient, a sampled surface's mesh against its formula, the extruded
//! disk's flat top and circular rim, and the column tops the TacTip reads.
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_shape3d::{
    numeric_gradient, Bowl, Extruded, Foil, HeightField, MeshFormat, Object3d, ObjectConfig,
    TriangleMesh, Vec3,
};

/// The report's disk: centre (5.5, -51.5), radius 55.2 mm.
const DISK: (f64, f64, f64) = (5.5, -51.5, 55.2);

fn disk(height: f64) -> Extruded {
    Extruded::new(builtin_shape(BuiltinShape::Disk), height).unwrap()
}

fn close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, want {want} (tol {tol})"
    );
}

#[test]
fn signed_distance_sign_and_magnitude_on_known_points() {
    let (cx, cy, r) = DISK;
    let d = disk(10.0);
    // The polygon is within 0.001 mm of the circle.
    close(
        d.signed_distance(Vec3::new(cx, cy, 5.0)),
        -5.0,
        1e-9,
        "disk centre",
    );
    close(
        d.signed_distance(Vec3::new(cx, cy, 13.0)),
        3.0,
        1e-9,
        "above the top",
    );
    close(
        d.signed_distance(Vec3::new(cx + 60.0, cy, 5.0)),
        60.0 - r,
        2e-3,
        "beside the wall",
    );
    close(
        d.signed_distance(Vec3::new(cx + r + 3.0, cy, 14.0)),
        5.0,
        2e-3,
        "over the rim (3-4-5)",
    );
    close(
        d.signed_distance(Vec3::new(cx, cy + r - 1.0, 8.0)),
        -1.0,
        2e-3,
        "inside near the wall",
    );

    let ramp = HeightField::ramp(0.0, 30.0, 0.0).unwrap();
    close(
        ramp.signed_distance(Vec3::new(0.0, 0.0, 2.0)),
        2.0 * 30f64.to_radians().cos(),
        1e-9,
        "ramp above",
    );
    close(
        ramp.signed_distance(Vec3::new(4.0, 7.0, -1.0 + 4.0 * 30f64.to_radians().tan())),
        -30f64.to_radians().cos(),
        1e-9,
        "ramp below",
    );

    let saddle = HeightField::saddle(50.0).unwrap();
    close(
        saddle.signed_distance(Vec3::new(0.0, 0.0, 3.0)),
        3.0,
        1e-9,
        "saddle above its centre",
    );
    assert!(
        saddle.signed_distance(Vec3::new(10.0, 0.0, 0.5)) < 0.0,
        "under the saddle's rising x branch"
    );
    assert!(
        saddle.signed_distance(Vec3::new(0.0, 10.0, -0.5)) > 0.0,
        "over the falling y branch"
    );

    let wave = HeightField::wave(2.0, 40.0, 0.0).unwrap();
    close(
        wave.signed_distance(Vec3::new(10.0, 3.0, 4.0)),
        2.0,
        1e-9,
        "over a crest",
    );
    close(
        wave.signed_distance(Vec3::new(30.0, -5.0, -3.0)),
        -1.0,
        1e-9,
        "under a trough",
    );

    let bowl = Bowl::new(40.0, 30.0).unwrap();
    let c = (40f64 * 40.0 - 30.0 * 30.0).sqrt();
    close(bowl.depth(), 40.0 - c, 1e-12, "bowl depth");
    close(
        bowl.signed_distance(Vec3::new(0.0, 0.0, -10.0)),
        40.0 - (c + 10.0),
        1e-9,
        "in the cavity",
    );
    close(
        bowl.signed_distance(Vec3::new(0.0, 0.0, -20.0)),
        40.0 - (c + 20.0),
        1e-9,
        "under the cavity",
    );
    close(
        bowl.signed_distance(Vec3::new(60.0, 0.0, 2.0)),
        2.0,
        1e-9,
        "over the flat top",
    );

    let foil = Foil::new(30.0, 60.0, 2.0).unwrap();
    close(
        foil.signed_distance(Vec3::new(0.0, 0.0, 4.0)),
        3.0,
        1e-9,
        "over the foil's crown",
    );
    close(
        foil.signed_distance(Vec3::new(0.0, 5.0, 0.0)),
        -1.0,
        1e-9,
        "mid-plate",
    );
    close(
        foil.signed_distance(Vec3::new(0.0, 35.0, 0.0)),
        5.0,
        1e-9,
        "beside the foil's edge",
    );
}

/// Points 1.5 mm either side of a surface point, off any edge.
fn around(q: Vec3, n: Vec3) -> [Vec3; 2] {
    [q + n * 1.5, q - n * 1.5]
}

#[test]
fn normals_of_analytic_surfaces_equal_the_distance_gradient() {
    let mut cases: Vec<(String, Box<dyn Object3d>, Vec<Vec3>)> = Vec::new();
    let grid: Vec<(f64, f64)> = (-3..=3)
        .flat_map(|i| (-3..=3).map(move |j| (7.0 * i as f64 + 0.3, 6.0 * j as f64 - 0.2)))
        .collect();
    for (name, hf) in [
        ("ramp", HeightField::ramp(1.0, 25.0, 40.0).unwrap()),
        ("saddle", HeightField::saddle(40.0).unwrap()),
        ("wave", HeightField::wave(1.5, 30.0, 20.0).unwrap()),
    ] {
        let points = grid
            .iter()
            .flat_map(|&(x, y)| around(Vec3::new(x, y, hf.height(x, y)), hf.surface_normal(x, y)))
            .collect();
        cases.push((name.into(), Box::new(hf), points));
    }
    let (cx, cy, r) = DISK;
    let mut prism = Vec::new();
    for k in 0..24 {
        let a = (k as f64 * 15.0 + 0.037).to_radians(); // off the vertices' bisectors
        let rim = Vec3::new(cx + r * a.cos(), cy + r * a.sin(), 5.0);
        prism.extend(around(rim, Vec3::new(a.cos(), a.sin(), 0.0)));
        prism.push(Vec3::new(
            cx + 0.5 * r * a.cos(),
            cy + 0.5 * r * a.sin(),
            11.0,
        ));
        prism.push(Vec3::new(
            cx + (r + 2.0) * a.cos(),
            cy + (r + 2.0) * a.sin(),
            12.0,
        ));
    }
    cases.push(("extruded disk".into(), Box::new(disk(10.0)), prism));
    let bowl = Bowl::new(40.0, 30.0).unwrap();
    let centre = Vec3::new(0.0, 0.0, (40f64 * 40.0 - 30.0 * 30.0).sqrt());
    let mut cavity = Vec::new();
    for (x, y) in grid.iter().map(|&(x, y)| (0.6 * x, 0.6 * y)) {
        let dir = Vec3::new(x, y, -30.0).normalize();
        let q = centre + dir * 40.0;
        cavity.extend(around(q, -dir));
        cavity.push(Vec3::new(45.0 + x, y, 1.2));
    }
    cases.push(("bowl".into(), Box::new(bowl), cavity));
    let foil = Foil::new(30.0, 60.0, 2.0).unwrap();
    let plate = grid
        .iter()
        .map(|&(x, y)| {
            Vec3::new(
                0.6 * x,
                0.6 * y,
                (61f64.powi(2) - (0.6 * x).powi(2)).sqrt() - 60.0 + 0.8,
            )
        })
        .collect();
    cases.push(("foil".into(), Box::new(foil), plate));

    for (name, object, points) in &cases {
        for p in points {
            let n = object.normal(*p);
            let g = numeric_gradient(object.as_ref(), *p);
            assert!(
                (n.norm() - 1.0).abs() < 1e-9,
                "{name}: normal at {p} not unit"
            );
            assert!(
                (n - g).norm() < 1e-4,
                "{name} at {p}: normal {n} vs gradient {g}"
            );
            let q = object.closest_point(*p);
            assert!(
                object.signed_distance(q).abs() < 1e-6,
                "{name}: closest point {q} off the surface"
            );
            let d = object.signed_distance(*p);
            assert!(
                ((p - q).norm() - d.abs()).abs() < 1e-6,
                "{name} at {p}: |p - q| != |sd|"
            );
        }
    }
}

#[test]
fn the_mesh_of_a_sampled_surface_agrees_with_its_formula_within_the_resolution() {
    for (name, hf) in [
        ("saddle", HeightField::saddle(50.0).unwrap()),
        ("wave", HeightField::wave(1.5, 40.0, 30.0).unwrap()),
    ] {
        let step = 1.0;
        let mesh = TriangleMesh::from_heights(30.0, step, |x, y| hf.height(x, y)).unwrap();
        // A linear interpolant over a cell of side h misses a surface of
        // curvature k by at most about k h^2 (both triangle diagonals).
        let curvature = hf.max_curvature();
        let tol = curvature * step * step;
        let mut worst: f64 = 0.0;
        for i in -8..=8 {
            for j in -8..=8 {
                let (x, y) = (2.3 * i as f64 + 0.17, 2.1 * j as f64 - 0.11);
                for dz in [-2.5, -0.7, 0.4, 3.0] {
                    let p = Vec3::new(x, y, hf.height(x, y) + dz);
                    let a = hf.signed_distance(p);
                    let m = mesh.signed_distance(p);
                    assert_eq!(a.signum(), m.signum(), "{name}: sign at {p}");
                    worst = worst.max((a - m).abs());
                }
            }
        }
        assert!(
            worst <= tol,
            "{name}: mesh and formula differ by {worst} mm > {tol}"
        );
        assert!(worst > 0.0, "{name}: the mesh must not be the formula");
    }
}

#[test]
fn an_extruded_disk_has_a_flat_top_and_its_rim_is_the_circle() {
    let (cx, cy, r) = DISK;
    let h = 12.0;
    let d = disk(h);
    for k in 0..36 {
        let a = k as f64 * 10f64.to_radians();
        let s = 0.9 * r * (k as f64 / 36.0);
        let p = Vec3::new(cx + s * a.cos(), cy + s * a.sin(), h + 2.0);
        let q = d.closest_point(p);
        close(q.z, h, 1e-12, "the top is flat");
        assert!((d.normal(p) - Vec3::z()).norm() < 1e-12, "the top faces up");
        // A plumb column meets the top at its height.
        let foot = Vec3::new(p.x, p.y, 0.0);
        close(d.column_top(foot, Vec3::z(), 100.0), h, 1e-12, "column top");
        assert!(
            d.footprint_distance(foot).unwrap() < 0.0,
            "inside the footprint"
        );
    }
    let edge = d.edge().unwrap();
    assert!(edge.closed && edge.samples.len() > 600);
    close(edge.length(), std::f64::consts::TAU * r, 0.05, "rim length");
    for s in &edge.samples {
        let radial = Vec3::new(s.point.x - cx, s.point.y - cy, 0.0);
        close(radial.norm(), r, 2e-3, "rim radius");
        close(s.point.z, h, 0.0, "rim height");
        let out = radial.normalize();
        assert!(s.tangent.dot(&out).abs() < 0.01, "tangent along the circle");
        assert!(
            s.tangent.cross(&out).z < 0.0,
            "counter-clockwise seen from above"
        );
        assert!((s.normals[0] - Vec3::z()).norm() < 1e-12, "top face normal");
        assert!((s.normals[1] - out).norm() < 0.01, "wall normal radial");
        // The edge frame: x out of the disk, y along the rim, z up.
        let f = s.frame();
        let axes = [
            f.rotation * Vec3::x(),
            f.rotation * Vec3::y(),
            f.rotation * Vec3::z(),
        ];
        assert!(
            (axes[0] - s.normals[1]).norm() < 1e-9,
            "frame x across the edge"
        );
        assert!(
            (axes[1] - s.tangent).norm() < 1e-9,
            "frame y along the edge"
        );
        assert!((axes[2] - Vec3::z()).norm() < 1e-9, "frame z up");
        let p = s.pose(tactrace_geometry::Pose::new(2.0, 0.0, -3.0, 0.0, 0.0, 0.0));
        let want = s.point + s.normals[1] * 2.0 - Vec3::z() * 3.0;
        assert!(
            (Vec3::new(p.x, p.y, p.z) - want).norm() < 1e-9,
            "edge pose position"
        );
        assert!(p.rx.abs() < 1e-9 && p.ry.abs() < 1e-9, "level edge pose");
    }
}

#[test]
fn column_tops_lie_on_the_surface_at_any_tilt() {
    let objects: Vec<(&str, Box<dyn Object3d>)> = vec![
        (
            "ramp",
            Box::new(HeightField::ramp(0.5, 20.0, 70.0).unwrap()),
        ),
        ("saddle", Box::new(HeightField::saddle(40.0).unwrap())),
        ("wave", Box::new(HeightField::wave(1.0, 25.0, 0.0).unwrap())),
        ("bowl", Box::new(Bowl::new(40.0, 30.0).unwrap())),
        ("foil", Box::new(Foil::new(30.0, 60.0, 2.0).unwrap())),
        ("disk", Box::new(disk(5.0))),
    ];
    let mesh = TriangleMesh::from_heights(30.0, 1.0, |x, y| 0.02 * x * y).unwrap();
    for (name, object) in objects
        .iter()
        .map(|(n, o)| (*n, o.as_ref()))
        .chain([("mesh", &mesh as &dyn Object3d)])
    {
        for (tilt, azimuth) in [(0.0, 0.0), (15.0, 30.0), (25.0, 200.0)] {
            let (t, a) = (f64::to_radians(tilt), f64::to_radians(azimuth));
            let axis = Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos());
            for (x, y) in [(0.0, 0.0), (3.0, -4.0), (-8.0, 6.0)] {
                let (x, y) = if name == "disk" {
                    (DISK.0 + x, DISK.1 + y)
                } else {
                    (x, y)
                };
                let foot = Vec3::new(x, y, -3.0);
                let top = object.column_top(foot, axis, 50.0);
                let on = foot + axis * top;
                let sd = object.signed_distance(on);
                assert!(
                    sd.abs() < 1e-6,
                    "{name} tilt {tilt}: column top {top} is {sd} mm off the surface"
                );
                assert!(
                    object.signed_distance(on + axis * 0.01) > 0.0,
                    "{name}: above the top is outside"
                );
            }
        }
    }
}

const CUBE_OBJ: &str =
    "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 0 0 10\nv 10 0 10\nv 10 10 10\nv 0 10 10\n\
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

fn cube_stl() -> String {
    let obj = TriangleMesh::from_bytes(CUBE_OBJ.as_bytes(), MeshFormat::Obj).unwrap();
    let mut s = String::from("solid cube\n");
    for t in obj.triangles() {
        s.push_str("facet normal 0 0 0\nouter loop\n");
        for &i in t {
            let v = obj.vertices()[i];
            s.push_str(&format!("vertex {} {} {}\n", v.x, v.y, v.z));
        }
        s.push_str("endloop\nendfacet\n");
    }
    s + "endsolid cube\n"
}

#[test]
fn meshes_read_from_stl_and_obj_give_a_cube_s_distances() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.stl");
    std::fs::write(&path, cube_stl()).unwrap();
    let from_obj = TriangleMesh::from_bytes(CUBE_OBJ.as_bytes(), MeshFormat::Obj).unwrap();
    let from_stl = TriangleMesh::read(&path).unwrap();
    for mesh in [&from_obj, &from_stl] {
        assert_eq!(mesh.triangles().len(), 12);
        close(
            mesh.signed_distance(Vec3::new(5.0, 5.0, 5.0)),
            -5.0,
            1e-12,
            "centre",
        );
        close(
            mesh.signed_distance(Vec3::new(5.0, 5.0, 13.0)),
            3.0,
            1e-12,
            "above",
        );
        close(
            mesh.signed_distance(Vec3::new(13.0, 14.0, 5.0)),
            5.0,
            1e-12,
            "beside an edge",
        );
        close(
            mesh.signed_distance(Vec3::new(11.0, 12.0, 12.0)),
            3.0,
            1e-12,
            "beyond a corner",
        );
        close(
            mesh.signed_distance(Vec3::new(9.0, 5.0, 8.0)),
            -1.0,
            1e-12,
            "inside near a face",
        );
        assert!((mesh.normal(Vec3::new(5.0, 5.0, 13.0)) - Vec3::z()).norm() < 1e-12);
        assert_eq!(
            mesh.sharp_edges(30.0).len(),
            12,
            "a cube has 12 sharp edges"
        );
    }
    let bad = TriangleMesh::from_bytes(
        b"solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0 nan\n",
        MeshFormat::Stl,
    );
    assert!(bad.is_err());
    let unknown = TriangleMesh::read(&dir.path().join("cube.ply")).unwrap_err();
    assert!(
        unknown.to_string().contains("unknown mesh format"),
        "{unknown}"
    );
}

#[test]
fn object_configs_parse_build_and_refuse_what_is_wrong() {
    let text = r#"
        [[object]]
        kind = "extruded"
        shape = "flower"
        height_mm = 20.0
        [[object]]
        kind = "ramp"
        height_mm = 0.0
        slope_deg = 15.0
        azimuth_deg = 90.0
        [[object]]
        kind = "saddle"
        radius_mm = 60.0
        [[object]]
        kind = "bowl"
        sphere_radius_mm = 50.0
        rim_radius_mm = 35.0
        [[object]]
        kind = "wave"
        amplitude_mm = 2.0
        wavelength_mm = 40.0
        azimuth_deg = 0.0
        [[object]]
        kind = "foil"
        outline_radius_mm = 30.0
        bend_radius_mm = 80.0
        thickness_mm = 1.5
    "#;
    #[derive(serde::Deserialize)]
    struct List {
        object: Vec<ObjectConfig>,
    }
    let list: List = toml::from_str(text).unwrap();
    assert_eq!(list.object.len(), 6);
    for cfg in &list.object {
        let object = cfg.build().unwrap();
        assert!(object.signed_distance(Vec3::new(0.0, 0.0, 500.0)) > 0.0);
    }
    let unknown =
        toml::from_str::<ObjectConfig>("kind = \"saddle\"\nradius_mm = 60.0\ncolour = 1\n");
    assert!(unknown.is_err(), "unknown fields are refused");
    let flat = ObjectConfig::Saddle { radius_mm: 5.0 }.build().unwrap_err();
    assert!(flat.to_string().contains("radius_mm = 5"), "{flat}");
    let steep = ObjectConfig::Wave {
        amplitude_mm: 10.0,
        wavelength_mm: 20.0,
        azimuth_deg: 0.0,
    };
    assert!(steep.build().is_err());
    let missing = ObjectConfig::Mesh {
        path: "no/such/mesh.stl".into(),
    }
    .build()
    .unwrap_err();
    assert!(
        missing.to_string().contains("cannot read the mesh"),
        "{missing}"
    );
}
