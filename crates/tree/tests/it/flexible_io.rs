//! The model file's `[body.flexible]` and the modes file: read into the same `FlexModel` as
//! the API builds, every bad value reported at its file and line, the rigid reader refusing
//! flexible bodies, and the beam's modes written as a modes file giving the same dynamics.

use satsim_tree::flexible::{self, Beam, FlexData, FlexModel, Flexible, Modes};
use satsim_tree::io::{parse_flex_model, parse_model, parse_modes_file, write_modes_file};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Body, Hinge, ModelBuilder};
use std::path::{Path, PathBuf};

/// Line numbers matter: the text starts on line 1.
const MODEL: &str = r#"[[body]]
name = "bus"
mass = 100.0
inertia = [[10, 0, 0], [0, 10, 0], [0, 0, 10]]

[[body]]
name = "panel"
mass = 0.0
[body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = 2.0, EI = 500.0, rho_A = 5.0, modes = 3 }
damping = 0.005
stiffening = true

[[body]]
name = "tip"
mass = 1.0
inertia = [[0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01]]

[[hinge]]
name = "h1"
parent = "bus"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.5, 0.0]

[[hinge]]
name = "h2"
parent = "panel"
child = "tip"
axis = [1.0, 0.0, 0.0]
at = [0.0, 2.0, 0.0]
"#;

fn contract_beam() -> Beam {
    Beam {
        root: Vec3::zeros(),
        axis: Vec3::y(),
        bend: Vec3::z(),
        length: 2.0,
        ei: 500.0,
        rho_a: 5.0,
        modes: 3,
    }
}

fn builder() -> ModelBuilder {
    ModelBuilder::new(BaseKind::Free)
        .body(Body::new("bus", 100.0, Mat3::identity() * 10.0))
        .body(Body::new("panel", 0.0, Mat3::zeros()))
        .body(Body::new("tip", 1.0, Mat3::identity() * 0.01))
        .hinge(Hinge::revolute("h1", "bus", "panel", Vec3::x()).at(Vec3::new(0.0, 0.5, 0.0)))
        .hinge(Hinge::revolute("h2", "panel", "tip", Vec3::x()).at(Vec3::new(0.0, 2.0, 0.0)))
}

#[test]
fn the_contract_beam_reads_as_the_api_builds_it() {
    let read = parse_flex_model(MODEL, Path::new("flex.toml")).unwrap();
    let flex = [Flexible {
        body: "panel".into(),
        modes: Modes::Beam(contract_beam()),
        damping: 0.005,
        stiffening: true,
    }];
    let built = FlexModel::build(builder(), &flex).unwrap();
    assert_eq!(read, built);
    // Defaults: no damping, stiffening on.
    let bare = MODEL.replace("damping = 0.005\nstiffening = true\n", "");
    let read = parse_flex_model(&bare, Path::new("flex.toml")).unwrap();
    let flex = [Flexible {
        damping: 0.0,
        ..flex[0].clone()
    }];
    assert_eq!(read, FlexModel::build(builder(), &flex).unwrap());
    // An axis within 1e-6 of unit is normalised.
    let near = MODEL.replace(
        "axis = [0.0, 1.0, 0.0], bend",
        "axis = [0.0, 1.0000005, 0.0], bend",
    );
    assert_eq!(
        parse_flex_model(&near, Path::new("flex.toml")).unwrap(),
        built
    );
}

#[test]
fn the_rigid_reader_refuses_flexible_bodies_at_their_line() {
    let err = parse_model(MODEL, Path::new("flex.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with(
            "flex.toml:10: body `panel`: flexible bodies are read only by the flexible reader"
        ),
        "{err}"
    );
    assert!(err.contains("run the model in a scene"), "{err}");
}

fn error_of(text: &str) -> String {
    match parse_flex_model(text, Path::new("flex.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_flexible_values_name_file_and_line() {
    let cases: [(&str, &str, &str); 13] = [
        // Each value in range, but not together: at the beam's line, with what they make.
        (
            "length = 2.0",
            "length = 1e-300",
            "flex.toml:10: flexible body `panel`: beam: length 1e-300, EI 500 and rho_A 5 make a mass of 5e-300 kg, a moment of inertia of 0 kg m² and modes from inf to inf rad/s: out of the range",
        ),
        (
            "length = 2.0",
            "length = 1e300",
            "flex.toml:10: flexible body `panel`: beam: length 1e300, EI 500 and rho_A 5 make a mass of 5e300 kg, a moment of inertia of inf kg m²",
        ),
        (
            "EI = 500.0",
            "EI = -500.0",
            "flex.toml:10: body `panel`: beam.EI = -500 must be positive",
        ),
        (
            "rho_A = 5.0",
            "rho_A = 0.0",
            "flex.toml:10: body `panel`: beam.rho_A = 0 must be positive",
        ),
        (
            "length = 2.0",
            "length = -2.0",
            "flex.toml:10: body `panel`: beam.length = -2 must be positive",
        ),
        (
            "bend = [0.0, 0.0, 1.0]",
            "bend = [0.0, 0.6, 0.8]",
            "flex.toml:10: body `panel`: beam.bend must be perpendicular to beam.axis",
        ),
        (
            "axis = [0.0, 1.0, 0.0], bend",
            "axis = [0.0, 2.0, 0.0], bend",
            "flex.toml:10: body `panel`: beam.axis [0.0, 2.0, 0.0] must be a unit vector",
        ),
        (
            "modes = 3",
            "modes = 0",
            "flex.toml:10: body `panel`: beam.modes = 0: 1 to 12 modes are supported",
        ),
        (
            "modes = 3",
            "modes = 13",
            "flex.toml:10: body `panel`: beam.modes = 13: 1 to 12 modes are supported",
        ),
        (
            "damping = 0.005",
            "damping = -0.1",
            "flex.toml:11: body `panel`: damping = -0.1 must be >= 0",
        ),
        (
            "stiffening = true",
            "stiffening = true\nmodes_file = \"m.toml\"",
            "flex.toml:13: body `panel`: give `beam` or `modes_file`, not both",
        ),
        ("stiffening = true", "stiffening = 1", "flex.toml:12: "),
        ("EI = 500.0", "EI = 500.0, ei = 1.0", "flex.toml:10: "),
    ];
    for (from, to, expected) in cases {
        assert!(MODEL.contains(from));
        let err = error_of(&MODEL.replacen(from, to, 1));
        assert!(err.starts_with(expected), "{to}: {err}");
    }
    // Neither `beam` nor `modes_file`.
    let beam_line = MODEL.lines().nth(9).unwrap();
    let err = error_of(&MODEL.replace(beam_line, "# no beam"));
    // At the table's header.
    assert!(
        err.starts_with("flex.toml:9: body `panel`: [body.flexible] needs `beam` or `modes_file`"),
        "{err}"
    );
}

/// The rigid part of a flexible body is checked as written: the beam's or the modes' mass,
/// added to it, would hide a negative mass or inertia in the sum (the panel's beam is 10 kg).
#[test]
fn a_flexible_bodys_rigid_part_is_checked_before_its_modes_add_to_it() {
    let negative = MODEL.replacen(
        "mass = 0.0",
        "mass = -1.0\ninertia = [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]",
        1,
    );
    assert_eq!(
        error_of(&negative),
        "flex.toml:8: body `panel`: mass -1 is negative"
    );
    let inertia = MODEL.replacen(
        "mass = 0.0",
        "mass = 1.0\ninertia = [[-0.5, 0, 0], [0, 1, 0], [0, 0, 1]]",
        1,
    );
    let err = error_of(&inertia);
    assert!(
        err.starts_with("flex.toml:9: body `panel`: ") && err.contains("-0.5"),
        "{err}"
    );
    // The same through a modes file.
    let dir = scratch("rigid_part");
    std::fs::write(
        dir.join("m.toml"),
        write_modes_file(&contract_beam(), None, &example_nodes()),
    )
    .unwrap();
    let beam_line = MODEL.lines().nth(9).unwrap();
    let with_file = negative
        .replace(beam_line, "modes_file = \"m.toml\"")
        .replace("damping = 0.005\n", "");
    let err = parse_flex_model(&with_file, &dir.join("flex.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.ends_with("flex.toml:8: body `panel`: mass -1 is negative"),
        "{err}"
    );
}

/// A scratch folder of this test process.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("satsim_flex_io_{}_{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn example_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/modes/panel_beam_modes.toml")
}

/// A model file's path in `examples/`, whose `modes/panel_beam_modes.toml` is the example.
fn examples_model_path() -> PathBuf {
    example_path()
        .parent()
        .unwrap()
        .parent()
        .unwrap()
        .join("flex.toml")
}

fn example_nodes() -> [(&'static str, Vec3); 3] {
    [
        ("root", Vec3::zeros()),
        ("middle", Vec3::new(0.0, 1.0, 0.0)),
        ("tip", Vec3::new(0.0, 2.0, 0.0)),
    ]
}

/// The ABA's and CRBA's results of two models agree to `1e-12` of their scale at a state
/// away from symmetry.
/// Whether `a` and `b` give the same accelerations (to 1e-12) at `same_dynamics`' state.
fn same_accelerations(a: &FlexModel, b: &FlexModel) -> bool {
    let (q, v, tau) = test_state(a);
    let xa = flexible::aba(a, &mut FlexData::new(a), &q, &v, &tau, None)
        .unwrap()
        .clone();
    let xb = flexible::aba(b, &mut FlexData::new(b), &q, &v, &tau, None)
        .unwrap()
        .clone();
    (&xa - &xb).amax() <= 1e-12 * xa.amax()
}

/// A spinning, deformed state of the test model.
fn test_state(a: &FlexModel) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut q = a.neutral();
    let nq = a.rigid().nq();
    q[7..nq].copy_from_slice(&[0.3, -0.2]);
    for (k, x) in q[nq..].iter_mut().enumerate() {
        *x = 0.01 * (1.0 + k as f64).cos();
    }
    let v: Vec<f64> = (0..a.nv()).map(|k| 0.2 * (1.0 + k as f64).sin()).collect();
    let tau: Vec<f64> = (0..a.nv()).map(|k| (2.0 + k as f64).cos()).collect();
    (q, v, tau)
}

fn same_dynamics(a: &FlexModel, b: &FlexModel) {
    assert_eq!((a.nq(), a.nv()), (b.nq(), b.nv()));
    let (q, v, tau) = test_state(a);
    let (mut da, mut db) = (FlexData::new(a), FlexData::new(b));
    let xa = flexible::aba(a, &mut da, &q, &v, &tau, None)
        .unwrap()
        .clone();
    let xb = flexible::aba(b, &mut db, &q, &v, &tau, None)
        .unwrap()
        .clone();
    let scale = xa.amax();
    assert!((&xa - &xb).amax() <= 1e-12 * scale, "{xa} vs {xb}");
    let ma = flexible::crba(a, &mut da, &q).unwrap().clone();
    let mb = flexible::crba(b, &mut db, &q).unwrap().clone();
    assert!((&ma - &mb).amax() <= 1e-12 * ma.amax());
}

#[test]
fn the_beam_as_a_modes_file_gives_the_same_dynamics() {
    let written = write_modes_file(&contract_beam(), None, &example_nodes());
    if std::env::var_os("SATSIM_WRITE_EXAMPLES").is_some() {
        std::fs::write(example_path(), &written).unwrap();
    }
    let committed = std::fs::read_to_string(example_path()).unwrap();
    assert_eq!(
        written, committed,
        "examples/modes/panel_beam_modes.toml is stale"
    );

    // The file's [stiffening] block: the beam's dynamics, spinning and deformed (the
    // state `same_dynamics` takes), with the stiffening on, its default for both.
    let beam_line = MODEL.lines().nth(9).unwrap();
    let origin = examples_model_path();
    let stiff = parse_flex_model(
        &MODEL.replace("stiffening = true\n", ""),
        Path::new("flex.toml"),
    )
    .unwrap();
    let given = MODEL
        .replace(beam_line, "modes_file = \"modes/panel_beam_modes.toml\"")
        .replace("stiffening = true\n", "");
    let from_file = parse_flex_model(&given, &origin).unwrap();
    same_dynamics(&stiff, &from_file);
    // And without: the stiffening off in both, which the spinning state tells apart.
    let beam = MODEL.replace("stiffening = true", "stiffening = false");
    let a = parse_flex_model(&beam, Path::new("flex.toml")).unwrap();
    let given = beam.replace(beam_line, "modes_file = \"modes/panel_beam_modes.toml\"");
    let b = parse_flex_model(&given, &origin).unwrap();
    same_dynamics(&a, &b);
    assert!(
        !same_accelerations(&a, &stiff),
        "the stiffening changed nothing"
    );
    // A file without the block: `stiffening = true` is refused at its line.
    let dir = scratch("unstiff");
    let bare: String = written
        .split("\n# The second-order inertia")
        .next()
        .unwrap()
        .to_owned()
        + &written[written.find("\n[[node]]").unwrap()..];
    assert!(!bare.contains("[stiffening]"));
    std::fs::write(dir.join("m.toml"), &bare).unwrap();
    let err = parse_flex_model(
        &MODEL.replace(beam_line, "modes_file = \"m.toml\""),
        &dir.join("flex.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("flex.toml:12: body `panel`: `stiffening = true`: the modes file")
            && err.contains("has no [stiffening] block"),
        "{err}"
    );
    // Left out, the bare file's modes do not stiffen: the beam's without stiffening.
    let c = parse_flex_model(
        &beam
            .replace(beam_line, "modes_file = \"m.toml\"")
            .replace("stiffening = false\n", ""),
        &dir.join("flex.toml"),
    )
    .unwrap();
    same_dynamics(&a, &c);
    std::fs::remove_dir_all(dir).unwrap();
    assert_eq!(a.damping().len(), 3);
    for (x, y) in a.damping().iter().zip(b.damping()) {
        assert!((x - y).abs() <= 1e-12 * x, "{x} vs {y}");
    }

    // Per-mode damping from the file.
    let dir = scratch("damped");
    let damped = write_modes_file(&contract_beam(), Some(0.005), &example_nodes());
    std::fs::write(dir.join("m.toml"), damped).unwrap();
    let given = beam
        .replace(beam_line, "modes_file = \"m.toml\"")
        .replace("damping = 0.005\n", "");
    let c = parse_flex_model(&given, &dir.join("flex.toml")).unwrap();
    same_dynamics(&a, &c);
    for (x, y) in a.damping().iter().zip(c.damping()) {
        assert!((x - y).abs() <= 1e-12 * x, "{x} vs {y}");
    }
    // Both the body's and the file's damping: refused at the body's key.
    let both = beam.replace(beam_line, "modes_file = \"m.toml\"");
    let err = parse_flex_model(&both, &dir.join("flex.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("flex.toml:11: body `panel`: damping is given both"),
        "{err}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A modes file's fixed-length arrays with too many entries are refused at their line, as
/// those with too few are: a `momentum` row of 7 is not read as its first 6.
#[test]
fn modes_file_arrays_of_the_wrong_length_name_their_line() {
    let good = write_modes_file(&contract_beam(), None, &example_nodes());
    parse_modes_file(&good, Path::new("m.toml")).unwrap();
    let line_of =
        |text: &str, key: &str| text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
    let com = good.lines().find(|l| l.starts_with("com = ")).unwrap();
    let three = "invalid length 4, expected an array of length 3";
    for (text, key, below, expected) in [
        (
            good.replacen("com = [", "com = [0.0, ", 1),
            "com",
            0,
            format!("`com`: {three}"),
        ),
        (
            good.replacen(com, "com = [0.0, 1.0, 0.0, \"junk\"]", 1),
            "com",
            0,
            format!("`com`: {three}"),
        ),
        (
            good.replacen(com, "com = [0.0, 1.0]", 1),
            "com",
            0,
            "`com`: invalid length 2, expected an array of length 3".to_owned(),
        ),
        (
            good.replacen("momentum = [\n  [", "momentum = [\n  [0.0, ", 1),
            "momentum",
            1,
            "`momentum`: invalid length 7, expected an array of length 6".to_owned(),
        ),
        (
            good.replacen("inertia = [[", "inertia = [[0.0, ", 1),
            "inertia",
            0,
            format!("`inertia`: {three}"),
        ),
        (
            good.replacen("axis = [", "axis = [0.0, ", 1),
            "axis",
            0,
            format!("`stiffening.axis`: {three}"),
        ),
        (
            good.replacen("at = [", "at = [0.0, ", 1),
            "at",
            0,
            format!("`node.at`: {three}"),
        ),
        (
            good.replacen("translation = [[", "translation = [[0.0, ", 1),
            "translation",
            0,
            format!("`node.translation`: {three}"),
        ),
    ] {
        let err = parse_modes_file(&text, Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        let line = line_of(&text, key) + below;
        assert_eq!(err, format!("m.toml:{line}: {expected}"));
    }
}

#[test]
fn bad_modes_files_name_their_file_and_line() {
    let dir = scratch("bad");
    let good = write_modes_file(&contract_beam(), None, &example_nodes());
    let beam_line = MODEL.lines().nth(9).unwrap();
    let model = MODEL
        .replace(beam_line, "modes_file = \"m.toml\"")
        .replace("damping = 0.005\n", "");
    let origin = dir.join("flex.toml");
    let m = dir.join("m.toml");
    let line_of =
        |text: &str, key: &str| text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
    let read = |text: &str| {
        std::fs::write(&m, text).unwrap();
        parse_flex_model(&model, &origin).unwrap_err().to_string()
    };
    let path = m.display().to_string();
    // The good file reads.
    std::fs::write(&m, &good).unwrap();
    parse_flex_model(&model, &origin).unwrap();
    // `key = value` in place of the line starting with `key = `.
    let set = |key: &str, value: &str| {
        let line = good
            .lines()
            .find(|l| l.starts_with(&format!("{key} = ")))
            .unwrap();
        good.replacen(line, &format!("{key} = {value}"), 1)
    };
    for (text, key, expected) in [
        (
            set("frequencies_hz", "[]"),
            "frequencies_hz",
            "`frequencies_hz`: at least one mode",
        ),
        (
            set("frequencies_hz", "[-1.0, 2.0, 3.0]"),
            "frequencies_hz",
            "`frequencies_hz`: each must be positive",
        ),
        (set("mass", "0.0"), "mass", "`mass` must be positive"),
        // The structure's inertia is checked as a body's, at its own line, not in the sum
        // with the body's rigid part (where a negative moment hides).
        (
            set(
                "inertia",
                "[[-3.3333333333333335, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 3.3333333333333335]]",
            ),
            "inertia",
            "`inertia` is not positive semi-definite (principal moment -3.3333333333333335)",
        ),
        (
            set(
                "inertia",
                "[[3.3333333333333335, 0.0, 0.0], [0.0, 9.0, 0.0], [0.0, 0.0, 3.3333333333333335]]",
            ),
            "inertia",
            "`inertia`: principal moments [3.3333333333333335, 3.3333333333333335, 9.0] break the triangle inequality",
        ),
        (
            set(
                "inertia",
                "[[3.3333333333333335, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 3.3333333333333335]]",
            ),
            "inertia",
            "`inertia` is not symmetric",
        ),
        (
            good.replacen("mass = ", "damping = [0.1]\nmass = ", 1),
            "damping",
            "`damping`: 3 entries expected",
        ),
        (
            set("s1", "[1.0]"),
            "s1",
            "`stiffening.s1`: 3 entries expected",
        ),
        (
            set("bend", "[0.0, 1.0, 0.0]"),
            "bend",
            "`stiffening.bend` must be normal to `axis`",
        ),
        (
            set("axis", "[0.0, 2.0, 0.0]"),
            "axis",
            "`stiffening.axis` must be a unit vector",
        ),
        (
            good.replacen("j0 = [\n  [", "j0 = [\n  [7.0, ", 1),
            "j0",
            "`stiffening.j0`: 3 rows of 3 expected",
        ),
        (
            good.replacen("j1 = [\n  [", "j1 = [\n  [-", 1),
            "j1",
            "`stiffening.j1` must be positive semi-definite",
        ),
    ] {
        let err = read(&text);
        let line = line_of(&text, key);
        assert!(
            err.starts_with(&format!("{path}:{line}: {expected}")),
            "{err}"
        );
    }
    let cases = [
        (
            "momentum = [\n",
            "momentum = [\n  [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],\n",
            "momentum",
            "`momentum`: 3 rows (one per mode) expected",
        ),
        (
            "translation = [",
            "translation = [[0.0, 0.0, 0.0], ",
            "translation",
            "node `root`: `translation`: 3 rows (one per mode) expected",
        ),
    ];
    for (from, to, key, expected) in cases {
        let text = good.replacen(from, to, 1);
        let err = read(&text);
        let line = line_of(&text, key);
        assert!(
            err.starts_with(&format!("{path}:{line}: {expected}")),
            "{err}"
        );
    }
    // Syntax and schema errors.
    let err = read(&good.replacen("mass = ", "mass = = ", 1));
    assert!(
        err.starts_with(&format!("{path}:{}: syntax error", line_of(&good, "mass"))),
        "{err}"
    );
    let err = read(&good.replacen("mass = ", "weight = 1.0\nmass = ", 1));
    assert!(
        err.starts_with(&format!("{path}:")) && err.contains("unknown key `weight`"),
        "{err}"
    );
    // A child hinge at no node: at the hinge's `at` line of the model file.
    let err = read(
        &good
            .replace("name = \"tip\"", "name = \"end\"")
            .replace("at = [0.0, 2.0, 0.0]", "at = [0.0, 1.9, 0.0]"),
    );
    assert!(
        err.starts_with(&format!("{}:30: hinge `h2`: its point [0.0, 2.0, 0.0] on the flexible body `panel` is none of the nodes", origin.display())),
        "{err}"
    );
    // A missing modes file: the model's fault, at its `modes_file` line (10).
    std::fs::remove_file(&m).unwrap();
    let err = parse_flex_model(&model, &origin).unwrap_err().to_string();
    assert!(
        err.starts_with(&format!(
            "{}:10: body `panel`: `modes_file` = \"m.toml\" ({path}): cannot read it: ",
            origin.display()
        )),
        "{err}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A beam far lighter than the body it carries: its shapes, each of unit modal mass, move the
/// tip by `1/√m` per unit coordinate, the tip's inertia drowns the beam's in round-off, and
/// the dynamics cannot resolve its modes (every run would fail at its first step in "mass
/// matrix is not positive definite"). Refused at the beam's line, naming the mode.
#[test]
fn a_beam_far_lighter_than_what_it_carries_is_refused_at_its_line() {
    let light = MODEL.replace("rho_A = 5.0", "rho_A = 1e-17");
    let err = error_of(&light);
    assert!(
        err.starts_with(
            "flex.toml:10: flexible body `panel`: at rest the dynamics cannot resolve its mode 1 \
             (its articulated pivot is 0, where the mass matrix makes it positive): each mode \
             has unit modal mass, so the shapes of a body far lighter than the bodies it carries"
        ),
        "{err}"
    );
    // Light (a beam of 2 mg under a 1 kg tip) but resolved: built, and its dynamics run.
    let model = parse_flex_model(
        &MODEL.replace("rho_A = 5.0", "rho_A = 1e-6"),
        Path::new("flex.toml"),
    )
    .expect("a light beam the dynamics resolve");
    let mut data = FlexData::new(&model);
    let (q, zero) = (model.neutral(), vec![0.0; model.nv()]);
    let ddq = flexible::aba(&model, &mut data, &q, &zero, &zero, None).expect("resolved");
    assert!(ddq.iter().all(|a| a.is_finite()));
    // Its coordinates in words, as a run's errors name them.
    let names: Vec<String> = [0, 5, 6, 7, 8, 9, 10, 11]
        .map(|k| model.coordinate(k))
        .into();
    assert_eq!(
        names,
        [
            "the base's angular velocity x",
            "the base's velocity z",
            "hinge `h1`",
            "hinge `h2`",
            "body `panel`'s mode 1",
            "body `panel`'s mode 2",
            "body `panel`'s mode 3",
            "coordinate 11",
        ]
    );
}

/// A body whose modes come from a file is watched at the file's nodes off its frame's
/// origin: its deflection is the node displaced most for its distance from the frame. The
/// contract beam written as a modes file (nodes at its root, middle and tip) gives, at any
/// deformation, the larger of the beam's own deflections at 1 m and 2 m for those
/// distances, and with its first mode alone the beam's tip fraction itself; the root's
/// node (at the origin) is not watched.
#[test]
fn a_modes_file_body_is_watched_at_its_nodes() {
    use satsim_tree::flexible::SMALL_DEFLECTION;
    let beam_line = MODEL.lines().nth(9).unwrap();
    let origin = examples_model_path();
    let beam = parse_flex_model(MODEL, Path::new("flex.toml")).unwrap();
    let given = parse_flex_model(
        &MODEL
            .replace(beam_line, "modes_file = \"modes/panel_beam_modes.toml\"")
            .replace("stiffening = true\n", ""),
        &origin,
    )
    .unwrap();
    let panel = 1;
    assert!(given.watched(panel) && !given.watched(0) && !given.watched(2));
    let names: Vec<&str> = given
        .watch_points(panel)
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(names, ["middle", "tip"]);
    assert!(given.tip_deflection(panel, &given.neutral()).is_none());
    let shape = |at: Vec3| contract_beam().node(&at).phi;
    let mut rng = 0x9e37_79b9_7f4a_7c15_u64;
    for _ in 0..20 {
        let eta: Vec<f64> = (0..3)
            .map(|_| {
                rng = rng.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                ((rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.4
            })
            .collect();
        let at = |p: Vec3| -> f64 {
            let d: Vec3 = shape(p).iter().zip(&eta).map(|(s, e)| s * *e).sum();
            d.norm() / p.norm()
        };
        let (middle, tip) = (at(Vec3::new(0.0, 1.0, 0.0)), at(Vec3::new(0.0, 2.0, 0.0)));
        let d = given.deflection_of(panel, &eta).unwrap();
        assert!(
            (d.fraction() - middle.max(tip)).abs() <= 1e-12,
            "{d:?} {middle} {tip}"
        );
        assert_eq!(d.point, Some(if tip >= middle { 1 } else { 0 }));
    }
    // The first mode alone: the tip is bent most for its distance, as the beam's own tip.
    let eta = [0.4, 0.0, 0.0];
    let (a, b) = (
        beam.deflection_of(panel, &eta).unwrap(),
        given.deflection_of(panel, &eta).unwrap(),
    );
    assert_eq!(
        (a.point, a.length, b.point, b.length),
        (None, 2.0, Some(1), 2.0)
    );
    assert!(
        (a.offset.abs() - b.offset).abs() <= 1e-12 * b.offset,
        "{a:?} {b:?}"
    );
    // Past a tenth: listed with the node, as the beam is with its tip.
    let mut q = given.neutral();
    let nq = given.rigid().nq();
    q[nq] = 1.1 * SMALL_DEFLECTION * 2.0 / b.offset * 0.4;
    let large = given.large_deflections(&q);
    assert_eq!(large.len(), 1, "{large:?}");
    assert_eq!((large[0].body, large[0].point), (panel, Some(1)));
    assert!((large[0].tip / large[0].length - 1.1 * SMALL_DEFLECTION).abs() < 1e-12);
    q[nq] *= 0.9 / 1.1;
    assert!(given.large_deflections(&q).is_empty());
    // Through the API, a point's translations must match the modes.
    let mut spec = given.flexible().to_vec();
    let Modes::Given { watch, .. } = &mut spec[0].modes else {
        panic!("given modes")
    };
    watch[2].translation.pop();
    let err = FlexModel::attach(given.rigid().clone(), &spec).unwrap_err();
    assert!(
        err.to_string()
            .contains("watched point `tip`: 2 translations for 3 modes"),
        "{err}"
    );
}
