use super::*;
use nalgebra::{Quaternion, Vector3};
use satsim_tree::samples::chain;
use satsim_tree::{Body, BoxShape, Hinge, ModelBuilder};

fn cols(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

fn number(x: f64) -> String {
    let mut s = String::new();
    push_number(&mut s, x);
    s
}

#[test]
fn numbers_are_kept_to_1e_9_without_trailing_zeros() {
    assert_eq!(number(1.0), "1");
    assert_eq!(number(-2.5), "-2.5");
    assert_eq!(number(0.123_456_789_123), "0.123456789");
    assert_eq!(number(-1e-10), "0");
    assert_eq!(number(1_000_000.5), "1000000.5");
    assert_eq!(number(1e-9), "0.000000001");
}

#[test]
fn the_inertia_box_has_the_bodys_inertia() {
    // A rotated, non-diagonal inertia: the box's own inertia, turned by its rotation, must
    // give it back.
    let r = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1)
        .to_rotation_matrix()
        .into_inner();
    let inertia = r * Mat3::from_diagonal(&Vec3::new(2.0, 5.0, 6.0)) * r.transpose();
    let m = 3.0;
    let b = inertia_box(m, &Vec3::new(0.1, 0.2, 0.3), &inertia).unwrap();
    let [a, bb, c] = b.size;
    let own = Mat3::from_diagonal(&Vec3::new(
        m / 12.0 * (bb * bb + c * c),
        m / 12.0 * (a * a + c * c),
        m / 12.0 * (a * a + bb * bb),
    ));
    let q = UnitQuaternion::from_quaternion(Quaternion::new(
        b.rotation[0],
        b.rotation[1],
        b.rotation[2],
        b.rotation[3],
    ))
    .to_rotation_matrix()
    .into_inner();
    assert!((q * own * q.transpose() - inertia).norm() < 1e-12);
    assert_eq!(b.centre, [0.1, 0.2, 0.3]);
    assert_eq!(b.from, "inertia");
    // A thin plate (I_z = I_x + I_y) keeps a visible thickness; a massless body is not drawn.
    let plate = inertia_box(
        20.0,
        &Vec3::zeros(),
        &Mat3::from_diagonal(&Vec3::new(1.0, 4.0, 5.0)),
    )
    .unwrap();
    let longest = plate.size.iter().copied().fold(0.0, f64::max);
    let thinnest = plate.size.iter().copied().fold(f64::INFINITY, f64::min);
    assert!((thinnest - 0.02 * longest).abs() < 1e-12, "{plate:?}");
    assert!(inertia_box(0.0, &Vec3::zeros(), &Mat3::identity()).is_none());
}

/// A fixed table with an arm turning about z: hinge at (0.5, 0, 0) on the table, at
/// (-1, 0, 0) on the arm.
fn arm() -> Model {
    ModelBuilder::new(BaseKind::Fixed)
        .body(
            Body::new("table", 10.0, Mat3::identity())
                .with_shape(BoxShape::new(Vec3::new(1.0, 1.0, 0.1)).at(Vec3::new(0.0, 0.0, -0.05))),
        )
        .body(Body::new(
            "arm",
            1.0,
            Mat3::from_diagonal(&Vec3::new(0.01, 0.1, 0.1)),
        ))
        .hinge(
            Hinge::revolute("h", "table", "arm", Vec3::z())
                .at(Vec3::new(0.5, 0.0, 0.0))
                .child_at(Vec3::new(-1.0, 0.0, 0.0)),
        )
        .build()
        .unwrap()
}

#[test]
fn poses_follow_the_hinge_kinematics() {
    let model = arm();
    let mut rec = PoseRecorder::new(&model, &cols(&["t", "angle_h", "rate_h"]), "arm").unwrap();
    let phis = [0.0, 0.4, -1.3, 2.9];
    for (k, phi) in phis.iter().enumerate() {
        rec.record(&[k as f64, *phi, 0.0]).unwrap();
    }
    let view = rec.finish(&[(1.5, "latched".into())]);
    assert_eq!(view.scene.origin, "inertial origin");
    assert_eq!(view.scene.angles, ["h"]);
    assert_eq!(view.scene.events[0].what, "latched");
    assert_eq!(view.frames.width, 1 + 1 + 14);
    for (k, phi) in phis.iter().enumerate() {
        let f = view.frames.frame(k);
        assert_eq!(f[0], k as f64);
        assert_eq!(f[1], *phi);
        // The table stays at the origin, unturned.
        assert_eq!(&f[2..9], &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
        // The arm's origin: hinge point + Rz(φ) (1, 0, 0); attitude Rz(φ).
        let expected = [0.5 + phi.cos(), phi.sin(), 0.0];
        for i in 0..3 {
            assert!((f[9 + i] - expected[i]).abs() < 1e-14, "{f:?}");
        }
        let q = [(phi / 2.0).cos(), 0.0, 0.0, (phi / 2.0).sin()];
        let sign = if f[12] * q[0] + f[15] * q[3] < 0.0 {
            -1.0
        } else {
            1.0
        };
        for i in 0..4 {
            assert!((f[12 + i] - sign * q[i]).abs() < 1e-14, "{f:?}");
        }
    }
    // The drawn boxes: the table's shape, the arm's inertia box along its principal axes.
    let table = view.scene.bodies[0].drawn.as_ref().unwrap();
    assert_eq!(
        (table.size, table.centre),
        ([1.0, 1.0, 0.1], [0.0, 0.0, -0.05])
    );
    assert_eq!(table.from, "shape");
    let h = &view.scene.hinges[0];
    assert_eq!(
        (h.body, h.axis, h.at),
        (1, [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0])
    );
}

#[test]
fn free_base_poses_are_about_the_centre_of_mass() {
    let model = chain(4, BaseKind::Free);
    let columns = cols(&[
        "t", "q_w", "q_x", "q_y", "q_z", "angle_h1", "angle_h2", "angle_h3",
    ]);
    let mut rec = PoseRecorder::new(&model, &columns, "chain").unwrap();
    let a = UnitQuaternion::from_euler_angles(0.2, 0.5, -0.4);
    rec.record(&[0.0, a.w, a.i, a.j, a.k, 0.3, -0.8, 1.7])
        .unwrap();
    let view = rec.finish(&[]);
    assert_eq!(view.scene.origin, "centre of mass");
    let f = view.frames.frame(0);
    let pose = |i: usize| {
        let o = 1 + 3 + 7 * i;
        let q = UnitQuaternion::from_quaternion(Quaternion::new(
            f[o + 3],
            f[o + 4],
            f[o + 5],
            f[o + 6],
        ));
        (Vector3::new(f[o], f[o + 1], f[o + 2]), q)
    };
    // Σ m (p + R com) = 0.
    let mut moment = Vec3::zeros();
    for (i, b) in model.bodies().iter().enumerate() {
        let (p, q) = pose(i);
        moment += b.mass() * (p + q * b.com());
    }
    assert!(moment.norm() < 1e-12, "{moment}");
    // The root's attitude is the row's; each hinge point is where both bodies put it
    // (h = r_p + R_p at = r_c + R_c child_at), and R_c = R_p Rot(axis, φ).
    assert!(pose(0).1.angle_to(&a) < 1e-12);
    for i in 1..model.n_bodies() {
        let j = model.joint(i).unwrap();
        let p = model.parent()[i].unwrap();
        let ((rp, qp), (rc, qc)) = (pose(p), pose(i));
        assert!(((rp + qp * j.at()) - (rc + qc * j.child_at())).norm() < 1e-12);
        let phi = f[1 + j.hinge()];
        let turn = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(*j.axis()), phi);
        assert!((qp * turn).angle_to(&qc) < 1e-12);
    }
}

#[test]
fn attitudes_are_sign_continuous() {
    let model = chain(1, BaseKind::Free);
    let columns = cols(&["t", "q_w", "q_x", "q_y", "q_z"]);
    let mut rec = PoseRecorder::new(&model, &columns, "spin").unwrap();
    for k in 0..50 {
        // Two full turns about z: the stored quaternion must not flip sign on the way.
        let q = UnitQuaternion::from_euler_angles(
            0.0,
            0.0,
            4.0 * std::f64::consts::PI * k as f64 / 49.0,
        );
        rec.record(&[k as f64, q.w, q.i, q.j, q.k]).unwrap();
    }
    let view = rec.finish(&[]);
    for k in 1..view.frames.len() {
        let (a, b) = (view.frames.frame(k - 1), view.frames.frame(k));
        let dot: f64 = (4..8).map(|i| a[i] * b[i]).sum();
        assert!(dot > 0.9, "frames {k}: {dot}");
    }
}

#[test]
fn long_runs_are_decimated_keeping_both_ends() {
    let model = arm();
    let mut rec = PoseRecorder::new(&model, &cols(&["t", "angle_h"]), "arm")
        .unwrap()
        .with_max_frames(8);
    for k in 0..101 {
        rec.record(&[k as f64, 0.01 * k as f64]).unwrap();
    }
    let view = rec.finish(&[]);
    let t: Vec<f64> = (0..view.frames.len())
        .map(|k| view.frames.frame(k)[0])
        .collect();
    assert!(t.len() <= 9 && t.len() >= 4, "{t:?}");
    assert_eq!((t[0], *t.last().unwrap()), (0.0, 100.0));
    // Kept rows are every stride-th row (a power of two), plus the last.
    let stride = t[1] - t[0];
    assert!(
        stride >= 16.0 && (stride as usize).is_power_of_two(),
        "{t:?}"
    );
    for w in t[..t.len() - 1].windows(2) {
        assert_eq!(w[1] - w[0], stride, "{t:?}");
    }
    // Each kept frame is the pose of its own row.
    for k in 0..view.frames.len() {
        let f = view.frames.frame(k);
        assert_eq!(f[1], 0.01 * f[0]);
    }
}

#[test]
fn non_finite_rows_are_not_kept() {
    let model = arm();
    let mut rec = PoseRecorder::new(&model, &cols(&["t", "angle_h"]), "arm").unwrap();
    rec.record(&[0.0, 0.1]).unwrap();
    rec.record(&[1.0, f64::NAN]).unwrap();
    let view = rec.finish(&[]);
    assert_eq!(view.frames.len(), 1);
    assert!(view.frames.data.iter().all(|x| x.is_finite()));
}

#[test]
fn the_recorder_needs_the_attitude_of_a_free_base() {
    let model = chain(2, BaseKind::Free);
    let e = PoseRecorder::new(&model, &cols(&["t", "angle_h1"]), "x")
        .err()
        .unwrap();
    assert_eq!(e.to_string(), "view: the rows have no `q_w` column");
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("satsim-view-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn the_kept_poses_give_back_the_same_page() {
    let mut builder = arm().to_builder();
    let evil = "arm</script><b>";
    builder.bodies_mut()[1].name = evil.into();
    builder.hinges_mut()[0].child = evil.into();
    let model = builder.build().unwrap();
    let mut rec = PoseRecorder::new(&model, &cols(&["t", "angle_h"]), "arm").unwrap();
    for k in 0..20 {
        rec.record(&[0.1 * k as f64, (0.1 * k as f64).sin()])
            .unwrap();
    }
    let view = rec.finish(&[(0.55, "stop `h`: latched".into())]);
    let dir = temp_dir("roundtrip");
    let page = view.write(&dir).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(!html.contains(PLACEHOLDER));
    // The body's name cannot close the data's <script> element.
    assert_eq!(
        html.matches("</script>").count(),
        TEMPLATE.matches("</script>").count()
    );
    assert!(html.contains("arm<\\/script><b>"));
    // No network: nothing is fetched from anywhere.
    for needle in [
        "http://",
        "https://",
        "src=\"",
        "fetch(",
        "XMLHttpRequest",
        "@import",
    ] {
        assert!(!html.contains(needle), "{needle}");
    }
    let back = ViewData::read(&dir).unwrap();
    assert_eq!(back.scene, view.scene);
    assert_eq!(back.frames.width, view.frames.width);
    for (a, b) in back.frames.data.iter().zip(&view.frames.data) {
        assert!((a - b).abs() <= 5e-10, "{a} {b}");
    }
    assert_eq!(back.html(), html);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_kept_files_are_named_with_their_line() {
    let model = arm();
    let mut rec = PoseRecorder::new(&model, &cols(&["t", "angle_h"]), "arm").unwrap();
    for k in 0..3 {
        rec.record(&[k as f64, 0.0]).unwrap();
    }
    let dir = temp_dir("bad");
    rec.finish(&[]).write(&dir).unwrap();
    let csv = dir.join(POSES_CSV);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    let broken = lines[2].replacen('0', "x", 1);
    lines[2] = &broken;
    std::fs::write(&csv, lines.join("\n")).unwrap();
    let e = ViewData::read(&dir).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}:3: ", csv.display())), "{e}");
    std::fs::write(&csv, "t,x\n").unwrap();
    let e = ViewData::read(&dir).unwrap_err().to_string();
    assert!(e.contains(":1: the header does not match view.json"), "{e}");
    std::fs::remove_file(dir.join(VIEW_JSON)).unwrap();
    let e = ViewData::read(&dir).unwrap_err().to_string();
    assert!(
        e.starts_with(&dir.join(VIEW_JSON).display().to_string()),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 2 m beam along the arm's x axis, bending along y, two modes.
fn arm_beam() -> Beam {
    Beam {
        root: Vec3::new(-1.0, 0.0, 0.0),
        axis: Vec3::x(),
        bend: Vec3::y(),
        length: 2.0,
        ei: 50.0,
        rho_a: 0.5,
        modes: 2,
    }
}

#[test]
fn beams_are_drawn_bent_by_their_modal_coordinates() {
    let model = arm();
    let columns = cols(&["t", "angle_h", "eta_arm_1", "eta_arm_2", "tip_arm"]);
    let rec = PoseRecorder::new(&model, &columns, "arm").unwrap();
    let mut rec = rec.with_beams(&[(1, arm_beam())], &columns).unwrap();
    let etas = [[0.0, 0.0], [0.3, 0.0], [0.0, -0.2], [0.1, 0.05]];
    for (k, e) in etas.iter().enumerate() {
        rec.record(&[k as f64, 0.1 * k as f64, e[0], e[1], 9.0])
            .unwrap();
    }
    let view = rec.finish(&[]);
    assert_eq!(view.frames.width, 1 + 1 + 14 + 2);
    let beam = &view.scene.beams[0];
    assert_eq!(beam.body, 1);
    assert_eq!(beam.points.len(), BEAM_POINTS);
    // A mass-normalised clamped-free mode of a uniform beam has φₙ(L) = 2 (−1)ⁿ⁺¹ / √(ρA L)
    // at the tip, and nothing at the clamped root.
    let tip = 2.0 / (0.5f64 * 2.0).sqrt();
    for (k, e) in etas.iter().enumerate() {
        let f = view.frames.frame(k);
        assert_eq!(&f[16..18], e);
        let line = beam.polyline(&f[16..18], 1.0);
        let root = line[0];
        assert!(
            root[0] == -1.0 && root[1].abs() < 1e-15 && root[2] == 0.0,
            "{root:?}"
        );
        let end = line[BEAM_POINTS - 1];
        assert!((end[0] - 1.0).abs() < 1e-15 && end[2] == 0.0, "{end:?}");
        let w = tip * (e[0] - e[1]);
        assert!((end[1] - w).abs() < 1e-12 * tip, "{} vs {w}", end[1]);
        // The exaggeration multiplies the deflection only.
        let big = beam.polyline(&f[16..18], 10.0)[BEAM_POINTS - 1];
        assert!((big[1] - 10.0 * w).abs() < 1e-11 * tip && big[0] == end[0]);
    }
    // The kept poses carry the modal coordinates and read back the same.
    let dir = temp_dir("beam");
    view.write(&dir).unwrap();
    let header = std::fs::read_to_string(dir.join(POSES_CSV)).unwrap();
    assert!(
        header
            .lines()
            .next()
            .unwrap()
            .ends_with(",eta_arm_1,eta_arm_2"),
        "{header}"
    );
    let back = ViewData::read(&dir).unwrap();
    assert_eq!(back.frames.width, view.frames.width);
    for (a, b) in back.frames.data.iter().zip(&view.frames.data) {
        assert!((a - b).abs() <= 5e-10, "{a} {b}");
    }
    let (a, b) = (&back.scene.beams[0], &view.scene.beams[0]);
    assert_eq!(
        (a.body, a.root, a.axis, a.bend),
        (b.body, b.root, b.axis, b.bend)
    );
    // JSON keeps the shapes to the last bit or so.
    for (x, y) in a.shapes.iter().flatten().zip(b.shapes.iter().flatten()) {
        assert!((x - y).abs() <= 1e-15 * tip, "{x} {y}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    // A scene without beams writes no `beams` key (older pages and files are unchanged).
    let plain = PoseRecorder::new(&model, &columns, "arm")
        .unwrap()
        .finish(&[]);
    assert!(
        !serde_json::to_string(&plain.scene)
            .unwrap()
            .contains("beams")
    );
    // The modal coordinates must be among the columns.
    let short = cols(&["t", "angle_h", "eta_arm_1"]);
    let e = PoseRecorder::new(&model, &short, "arm")
        .unwrap()
        .with_beams(&[(1, arm_beam())], &short)
        .err()
        .unwrap();
    assert!(e.to_string().contains("`eta_arm_2`"), "{e}");
}

#[test]
fn wheel_rotors_are_counted_apart_and_kept_in_view_json() {
    // chain(3): bodies b0, b1, b2 on hinges h1, h2; take the last as a rotor.
    let model = chain(3, BaseKind::Fixed);
    let columns = cols(&["t", "angle_h1", "angle_h2"]);
    let rec = PoseRecorder::new(&model, &columns, "c")
        .unwrap()
        .with_rotors(1)
        .unwrap();
    let view = rec.finish(&[]);
    assert_eq!(view.scene.rotors, 1);
    let json = serde_json::to_string(&view.scene).unwrap();
    assert!(json.contains("\"rotors\":1"), "{json}");
    // None: the key is left out, and a file without it reads as none.
    let plain = PoseRecorder::new(&model, &columns, "c")
        .unwrap()
        .finish(&[]);
    let json = serde_json::to_string(&plain.scene).unwrap();
    assert!(!json.contains("rotors"), "{json}");
    let back: ViewScene = serde_json::from_str(&json).unwrap();
    assert_eq!(back.rotors, 0);
    // More rotors than the model has bodies besides its root: refused.
    let e = PoseRecorder::new(&model, &columns, "c")
        .unwrap()
        .with_rotors(3)
        .err()
        .unwrap();
    assert_eq!(
        e.to_string(),
        "view: 3 wheel rotors in a model of 3 bodies and 2 hinges"
    );
}
