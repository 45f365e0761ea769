use super::*;
use crate::model::{BaseKind, Model};
use crate::spatial::Vec3;
use serde::Deserialize;
use std::path::Path;

/// A valid two-body model (`tests/fixtures/two_body.toml`, shared with the CLI's contract
/// tests): the bad inputs below are small edits of it.
/// Line numbers: 1 `[base]`, 4 `[[body]]` bus, 9 `[[body]]` panel, 14 `[[hinge]]`.
const GOOD: &str = include_str!("../../../../tests/fixtures/two_body.toml");

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Empty,
    Syntax,
    Schema,
    Model,
}

fn kind(e: &FileError) -> Kind {
    match e {
        FileError::Empty { .. } => Kind::Empty,
        FileError::Syntax { .. } => Kind::Syntax,
        FileError::Schema { .. } => Kind::Schema,
        FileError::Model { .. } => Kind::Model,
        other => panic!("unexpected error kind: {other}"),
    }
}

fn model_err(text: &str) -> FileError {
    match parse_model(text, Path::new("dir/bad.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

#[test]
fn good_model_builds() {
    let (m, f) = parse_model(GOOD, Path::new("good.toml")).unwrap();
    assert_eq!((m.nq(), m.nv(), m.n_bodies()), (8, 7, 2));
    assert_eq!(f.body.len(), 2);
    assert_eq!(f.base_kind(), BaseKind::Free);
    assert_eq!(line_of(GOOD, f.hinge[0].span().start), 14);
}

/// `GOOD` with `line` added after the panel's inertia (as line 13).
fn with_shape(line: &str) -> String {
    GOOD.replace(
        "inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]",
        &format!("inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]\n{line}"),
    )
}

#[test]
fn shapes_are_read_and_default_to_the_com() {
    let text = with_shape("com = [0, 1, 0]\nshape = { box = [0.02, 2, 1] }").replace(
        "inertia = [[40, 0, 0], [0, 40, 0], [0, 0, 30]]",
        "inertia = [[40, 0, 0], [0, 40, 0], [0, 0, 30]]\nshape = { box = [1.5, 1.5, 1], at = [0, 0, 0.25] }",
    );
    let (m, _) = parse_model(&text, Path::new("ok.toml")).unwrap();
    let bus = m.bodies[0].shape.unwrap();
    assert_eq!(bus.size, Vec3::new(1.5, 1.5, 1.0));
    assert_eq!(bus.centre(&m.bodies[0].com), Vec3::new(0.0, 0.0, 0.25));
    let panel = &m.bodies[1];
    let shape = panel.shape.unwrap();
    assert_eq!(shape.size, Vec3::new(0.02, 2.0, 1.0));
    assert_eq!(shape.at, None);
    assert_eq!(shape.centre(&panel.com), Vec3::new(0.0, 1.0, 0.0));
    // Drawing only: the dynamics are those of the model without shapes.
    let plain = parse_model(&text.replace("shape = ", "# shape = "), Path::new("p.toml"))
        .unwrap()
        .0;
    assert!(plain.bodies.iter().all(|b| b.shape.is_none()));
    assert_eq!(plain.bodies[1].inertia, panel.inertia);
    assert_eq!(plain.joints, m.joints);
    // A body without `shape` has none.
    assert!(model().bodies.iter().all(|b| b.shape.is_none()));
}

#[test]
fn facets_are_read_in_the_body_frame() {
    let text = with_shape(
        r#"com = [0, 1, 0]
shape = { box = [0.02, 2, 1] }
facets = [
  { area = 1.2, normal = [0.0, 0.0, 1.0000005], at = [0.0, 0.8, 0.0],
    specular = 0.3, diffuse = 0.1, drag = 2.0 },
  { size = [2, 0.5], edge = [0.3, 1, 0], normal = [1, 0, 0], at = [0.01, 1, 0] },
  { area = 2.0, size = [4, 0.5], normal = [0, -1, 0], at = [0, 0, 0] },
  { area = 9, edge = [1, 1, 0], normal = [0, 0, -1], at = [0, 0, -1] },
]
facets_from_shape = { specular = 0.5, diffuse = 0.25, drag = 1.5 }"#,
    );
    let (m, _) = parse_model(&text, Path::new("ok.toml")).unwrap();
    assert!(m.bodies[0].facets().is_empty());
    let f = m.bodies[1].facets();
    assert_eq!(f.len(), 4 + 6);
    // The contract's form: a square of side √1.2 on the least aligned axis (x), the
    // normal normalised from within 1e-6 of unit.
    assert_eq!(f[0].area, 1.2);
    assert_eq!(f[0].normal, Vec3::z());
    assert_eq!(f[0].at, Vec3::new(0.0, 0.8, 0.0));
    assert_eq!((f[0].specular, f[0].diffuse, f[0].drag), (0.3, 0.1, 2.0));
    let side = 1.2f64.sqrt();
    assert!((f[0].edges[0] - Vec3::x() * side).norm() < 1e-15);
    assert!((f[0].edges[1] - Vec3::y() * side).norm() < 1e-6 * side);
    // `size` with `edge`: 2 m along y (the edge projected into the plane), 0.5 m along
    // x × y = z; the area is their product; coefficients default.
    assert_eq!(f[1].area, 1.0);
    assert_eq!(
        f[1].edges,
        [Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 0.0, 0.5)]
    );
    assert_eq!((f[1].specular, f[1].diffuse, f[1].drag), (0.0, 0.0, 2.2));
    // `size` with a matching `area` and no `edge`: side a along the square's first side
    // (x, the least aligned axis with -y), side b along -y × x = z.
    assert_eq!(f[2].area, 2.0);
    assert_eq!(
        f[2].edges,
        [Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.5)]
    );
    // `edge` alone: a square of the given area turned to the edge.
    assert_eq!(f[3].area, 9.0);
    let d = Vec3::new(1.0, 1.0, 0.0).normalize() * 3.0;
    assert!((f[3].edges[0] - d).norm() < 1e-15);
    assert!((f[3].edges[1] - (-Vec3::z()).cross(&d)).norm() < 1e-15);
    // The six faces of the shape box (centred on the com), after the listed facets.
    let faces = crate::facet::facets_of_box(&m.bodies[1].shape.unwrap(), &m.bodies[1].com);
    for (k, face) in faces.iter().enumerate() {
        let g = &f[4 + k];
        assert_eq!(
            (g.area, g.normal, g.at, g.edges),
            (face.area, face.normal, face.at, face.edges)
        );
        assert_eq!((g.specular, g.diffuse, g.drag), (0.5, 0.25, 1.5));
    }
    assert_eq!(f[4].at, Vec3::new(0.01, 1.0, 0.0));
    assert_eq!(f[4].area, 2.0);
    // Facets are data: the dynamics are those of the model without them.
    let plain = parse_model(&with_shape("com = [0, 1, 0]"), Path::new("p.toml"))
        .unwrap()
        .0;
    assert_eq!(plain.bodies[1].inertia, m.bodies[1].inertia);
    assert_eq!(plain.joints, m.joints);
    // Rebuilding keeps them.
    assert_eq!(m.to_builder().build().unwrap(), m);
}

#[test]
fn model_error_table() {
    // (description, edited text, kind, line, substring of the message)
    let body3 =
        "\n[[body]]\nname = \"extra\"\nmass = 1.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n";
    let hinge2 = |parent: &str, child: &str| {
        format!(
            "\n[[hinge]]\nname = \"h2\"\nparent = \"{parent}\"\nchild = \"{child}\"\naxis = [0, 0, 1]\n"
        )
    };
    let cases: Vec<(&str, String, Kind, Option<usize>, &str)> = vec![
        ("empty", "  \n\n".into(), Kind::Empty, None, "empty"),
        (
            "toml syntax",
            GOOD.replace("mass = 20.0", "mass = = 20.0"),
            Kind::Syntax,
            Some(11),
            "syntax error",
        ),
        (
            "unterminated string",
            GOOD.replace("name = \"h\"", "name = \"h"),
            Kind::Syntax,
            Some(15),
            "syntax error",
        ),
        (
            "missing mass",
            GOOD.replace("mass = 20.0\n", ""),
            Kind::Schema,
            Some(9),
            "missing required key `mass`",
        ),
        (
            "missing axis",
            GOOD.replace("axis = [1, 0, 0]\n", ""),
            Kind::Schema,
            Some(14),
            "missing required key `axis`",
        ),
        (
            "missing name",
            GOOD.replace("name = \"panel\"\n", ""),
            Kind::Schema,
            Some(9),
            "missing required key `name`",
        ),
        (
            "missing inertia with mass",
            GOOD.replace("inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]\n", ""),
            Kind::Schema,
            Some(9),
            "body `panel`: missing key `inertia`",
        ),
        (
            "misspelt intertia",
            GOOD.replace("inertia = [[1.7", "intertia = [[1.7"),
            Kind::Schema,
            Some(12),
            "unknown key `intertia`",
        ),
        (
            "unknown top-level key",
            format!("gravity = 9.81\n{GOOD}"),
            Kind::Schema,
            Some(1),
            "unknown key `gravity`",
        ),
        (
            "unknown hinge key",
            GOOD.replace("at = [0, 1, 0]", "att = [0, 1, 0]"),
            Kind::Schema,
            Some(19),
            "unknown key `att`",
        ),
        (
            "mass of wrong type",
            GOOD.replace("mass = 20.0", "mass = \"heavy\""),
            Kind::Schema,
            Some(11),
            "`body.mass`: invalid type",
        ),
        (
            "vector of wrong length",
            GOOD.replace("at = [0, 1, 0]", "at = [0, 1]"),
            Kind::Schema,
            Some(19),
            "invalid length 2, expected an array of length 3",
        ),
        (
            "vector with too many entries",
            GOOD.replace("at = [0, 1, 0]", "at = [0, 1, 0, 5]"),
            Kind::Schema,
            Some(19),
            "invalid length 4, expected an array of length 3",
        ),
        (
            "axis with an entry not a number past its three",
            GOOD.replace("axis = [1, 0, 0]", "axis = [1, 0, 0, \"junk\"]"),
            Kind::Schema,
            Some(18),
            "`hinge.axis`: invalid length 4, expected an array of length 3",
        ),
        (
            "inertia row with too many entries",
            GOOD.replace("[[1.7, 0, 0]", "[[1.7, 0, 0, 99]"),
            Kind::Schema,
            Some(12),
            "`body.inertia`: invalid length 4, expected an array of length 3",
        ),
        (
            "inertia row with too many entries, on its own line",
            GOOD.replace(
                "inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]",
                "inertia = [\n  [1.7, 0, 0],\n  [0, 6.7, 0, 0],\n  [0, 0, 8.3],\n]",
            ),
            Kind::Schema,
            Some(14),
            "`body.inertia`: invalid length 4, expected an array of length 3",
        ),
        (
            "inertia with too many rows",
            GOOD.replace("[0, 0, 8.3]]", "[0, 0, 8.3], [0, 0, 0]]"),
            Kind::Schema,
            Some(12),
            "`body.inertia`: invalid length 4, expected an array of length 3",
        ),
        (
            "inertia row with too few entries",
            GOOD.replace("[0, 6.7, 0]", "[0, 6.7]"),
            Kind::Schema,
            Some(12),
            "`body.inertia`: invalid length 2, expected an array of length 3",
        ),
        (
            "unknown base kind",
            GOOD.replace("kind = \"free\"", "kind = \"floating\""),
            Kind::Schema,
            Some(2),
            "unknown value `floating`",
        ),
        (
            "duplicate body",
            GOOD.replace("name = \"panel\"", "name = \"bus\""),
            Kind::Model,
            Some(10),
            "duplicate body name `bus`",
        ),
        (
            "duplicate hinge",
            format!(
                "{GOOD}{body3}{}",
                hinge2("bus", "extra").replace("\"h2\"", "\"h\"")
            ),
            Kind::Model,
            Some(27),
            "duplicate hinge name `h`",
        ),
        (
            "unknown parent",
            GOOD.replace("parent = \"bus\"", "parent = \"bsu\""),
            Kind::Model,
            Some(16),
            "hinge `h`: unknown parent body `bsu`",
        ),
        (
            "unknown child",
            GOOD.replace("child = \"panel\"", "child = \"pannel\""),
            Kind::Model,
            Some(17),
            "unknown child body `pannel`",
        ),
        (
            "second root",
            format!("{GOOD}{body3}"),
            Kind::Model,
            Some(22),
            "body `extra` is the child of no hinge",
        ),
        (
            "two parents",
            format!("{GOOD}{}", hinge2("bus", "panel")),
            Kind::Model,
            Some(24),
            "body `panel` has two parents",
        ),
        (
            "root as child",
            format!("{GOOD}{}", hinge2("panel", "bus")),
            Kind::Model,
            Some(24),
            "makes the root body `bus` a child",
        ),
        (
            "cycle",
            format!(
                "{}{body3}{}",
                GOOD.replace("parent = \"bus\"", "parent = \"extra\""),
                hinge2("panel", "extra")
            ),
            Kind::Model,
            Some(10),
            "cycle",
        ),
        (
            "negative mass",
            GOOD.replace("mass = 20.0", "mass = -20.0"),
            Kind::Model,
            Some(11),
            "mass -20 is negative",
        ),
        (
            "non-finite mass",
            GOOD.replace("mass = 20.0", "mass = nan"),
            Kind::Model,
            Some(11),
            "body `panel`: mass: value is not finite",
        ),
        (
            "non-finite vector",
            GOOD.replace("at = [0, 1, 0]", "at = [0, inf, 0]"),
            Kind::Model,
            Some(19),
            "hinge `h`: at: value is not finite",
        ),
        (
            "non-symmetric inertia",
            GOOD.replace("[[1.7, 0, 0], [0, 6.7, 0]", "[[1.7, 0.5, 0], [0, 6.7, 0]"),
            Kind::Model,
            Some(12),
            "inertia is not symmetric",
        ),
        (
            "inertia not positive",
            GOOD.replace("[0, 0, 8.3]]", "[0, 0, -8.3]]"),
            Kind::Model,
            Some(12),
            "not positive semi-definite",
        ),
        (
            "inertia triangle",
            GOOD.replace("[0, 0, 8.3]]", "[0, 0, 9.3]]"),
            Kind::Model,
            Some(12),
            "triangle inequality",
        ),
        (
            "axis norm",
            GOOD.replace("axis = [1, 0, 0]", "axis = [1, 1, 0]"),
            Kind::Model,
            Some(18),
            "axis norm 1.41",
        ),
        (
            "rotation norm",
            GOOD.replace("at = [0, 1, 0]", "rotation = [1, 0, 0, 0.1]"),
            Kind::Model,
            Some(19),
            "rotation quaternion norm",
        ),
        (
            "shape with a zero size",
            with_shape("shape = { box = [0.02, 0, 1] }"),
            Kind::Model,
            Some(13),
            "body `panel`: shape box sizes [0.02, 0.0, 1.0] must all be positive",
        ),
        (
            "shape with a negative size",
            with_shape("shape = { box = [0.02, -2, 1], at = [0, 1, 0] }"),
            Kind::Model,
            Some(13),
            "must all be positive",
        ),
        (
            "shape with an unknown key",
            with_shape("shape = { box = [0.02, 2, 1], colour = \"red\" }"),
            Kind::Schema,
            Some(13),
            "unknown key `colour`",
        ),
        (
            "shape table with an unknown key on its own line",
            format!("{GOOD}\n[body.shape]\nbox = [0.02, 2, 1]\nsphere = 1.0\n"),
            Kind::Schema,
            Some(23),
            "unknown key `sphere`",
        ),
        (
            "shape without box",
            with_shape("shape = { at = [0, 1, 0] }"),
            Kind::Schema,
            Some(13),
            "missing required key `box`",
        ),
        (
            "shape box of two numbers",
            with_shape("shape = { box = [0.02, 2] }"),
            Kind::Schema,
            Some(13),
            "shape",
        ),
        (
            "shape at not finite",
            with_shape("shape = { box = [0.02, 2, 1], at = [0, nan, 0] }"),
            Kind::Model,
            Some(13),
            "body `panel`: shape.at: value is not finite",
        ),
        (
            "shape box not finite",
            with_shape("shape = { box = [0.02, inf, 1] }"),
            Kind::Model,
            Some(13),
            "body `panel`: shape.box: value is not finite",
        ),
        (
            "facet with zero area",
            with_shape("facets = [{ area = 0, normal = [0, 0, 1], at = [0, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "body `panel`: facet 0: area 0 must be positive",
        ),
        (
            "facet with negative area",
            with_shape("facets = [{ area = -1.5, normal = [0, 0, 1], at = [0, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "facet 0: area -1.5 must be positive",
        ),
        (
            "facet area not finite",
            with_shape("facets = [{ area = nan, normal = [0, 0, 1], at = [0, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "body `panel`: facet 0: area: value is not finite",
        ),
        (
            "facet normal not unit",
            with_shape("facets = [{ area = 1, normal = [0, 0, 2], at = [0, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "body `panel`: facet 0: normal norm 2 is not 1 (within 1e-6)",
        ),
        (
            "facet normal zero",
            with_shape("facets = [{ area = 1, normal = [0, 0, 0], at = [0, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "facet 0: normal norm 0 is not 1",
        ),
        (
            "facet normal not finite",
            with_shape("facets = [{ area = 1, normal = [0, inf, 1], at = [0, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "body `panel`: facet 0: normal: value is not finite",
        ),
        (
            "facet centroid not finite",
            with_shape("facets = [{ area = 1, normal = [0, 0, 1], at = [nan, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "body `panel`: facet 0: at: value is not finite",
        ),
        (
            "facet specular above 1",
            with_shape(
                "facets = [{ area = 1, normal = [0, 0, 1], at = [0, 0, 0], specular = 1.2 }]",
            ),
            Kind::Model,
            Some(13),
            "facet 0: specular 1.2 and diffuse 0 must each lie in [0, 1] and sum to at most 1",
        ),
        (
            "facet diffuse negative",
            with_shape(
                "facets = [{ area = 1, normal = [0, 0, 1], at = [0, 0, 0], diffuse = -0.1 }]",
            ),
            Kind::Model,
            Some(13),
            "specular 0 and diffuse -0.1 must each lie in [0, 1]",
        ),
        (
            "facet reflecting more than it receives",
            with_shape(
                "facets = [{ area = 1, normal = [0, 0, 1], at = [0, 0, 0], specular = 0.6, diffuse = 0.5 }]",
            ),
            Kind::Model,
            Some(13),
            "specular 0.6 and diffuse 0.5 must each lie in [0, 1] and sum to at most 1",
        ),
        (
            "facet specular not finite",
            with_shape(
                "facets = [{ area = 1, normal = [0, 0, 1], at = [0, 0, 0], specular = nan }]",
            ),
            Kind::Model,
            Some(13),
            "body `panel`: facet 0: specular: value is not finite",
        ),
        (
            "facet drag negative",
            with_shape("facets = [{ area = 1, normal = [0, 0, 1], at = [0, 0, 0], drag = -2.2 }]"),
            Kind::Model,
            Some(13),
            "body `panel`: facet 0: drag coefficient -2.2 is negative",
        ),
        (
            "facet drag not finite",
            with_shape("facets = [{ area = 1, normal = [0, 0, 1], at = [0, 0, 0], drag = inf }]"),
            Kind::Model,
            Some(13),
            "facet 0: drag: value is not finite",
        ),
        (
            "facet with an unknown key",
            with_shape("facets = [{ area = 1, normal = [0, 0, 1], at = [0, 0, 0], colour = 1 }]"),
            Kind::Schema,
            Some(13),
            "unknown key `colour`",
        ),
        (
            "facet without normal",
            with_shape("facets = [{ area = 1, at = [0, 0, 0] }]"),
            Kind::Schema,
            Some(13),
            "missing required key `normal`",
        ),
        (
            "facet without area or size",
            with_shape("facets = [{ normal = [0, 0, 1], at = [0, 0, 0] }]"),
            Kind::Schema,
            Some(13),
            "body `panel`: facet 0: missing key `area` (required unless `size` is given)",
        ),
        (
            "facet area not size[0] size[1]",
            with_shape(
                "facets = [{ area = 1.2, size = [1, 1.3], normal = [0, 0, 1], at = [0, 0, 0] }]",
            ),
            Kind::Schema,
            Some(13),
            "body `panel`: facet 0: area 1.2 is not size[0] · size[1] = 1.3",
        ),
        (
            "facet size not positive",
            with_shape("facets = [{ size = [1, 0], normal = [0, 0, 1], at = [0, 0, 0] }]"),
            Kind::Schema,
            Some(13),
            "facet 0: size [1, 0] must be positive",
        ),
        (
            "facet size not finite",
            with_shape("facets = [{ size = [1, inf], normal = [0, 0, 1], at = [0, 0, 0] }]"),
            Kind::Model,
            Some(13),
            "facet 0: size: value is not finite",
        ),
        (
            "facet edge along the normal",
            with_shape(
                "facets = [{ size = [1, 2], edge = [0, 0, -3], normal = [0, 0, 1], at = [0, 0, 0] }]",
            ),
            Kind::Schema,
            Some(13),
            "facet 0: edge [0.0, 0.0, -3.0] has no direction in the facet's plane",
        ),
        (
            "the second facet of a list, on its own line",
            with_shape(
                "facets = [\n  { area = 1, normal = [0, 0, 1], at = [0, 0, 0] },\n  { area = 1, normal = [0, 1, 1], at = [0, 0, 0] },\n]",
            ),
            Kind::Model,
            Some(15),
            "body `panel`: facet 1: normal norm 1.41",
        ),
        (
            "facets_from_shape without shape",
            with_shape("facets_from_shape = { specular = 0.3 }"),
            Kind::Schema,
            Some(13),
            "body `panel`: `facets_from_shape` requires a `shape`",
        ),
        (
            "facets_from_shape with an unknown key",
            with_shape(
                "shape = { box = [0.02, 2, 1] }\nfacets_from_shape = { specular = 0.3, absorbed = 0.7 }",
            ),
            Kind::Schema,
            Some(14),
            "unknown key `absorbed`",
        ),
        (
            "facets_from_shape with bad coefficients, after a listed facet",
            with_shape(
                "shape = { box = [0.02, 2, 1] }\nfacets = [{ area = 1, normal = [1, 0, 0], at = [0, 0, 0] }]\nfacets_from_shape = { specular = 0.7, diffuse = 0.7 }",
            ),
            Kind::Model,
            Some(15),
            "body `panel`: facet 1: specular 0.7 and diffuse 0.7",
        ),
        (
            "facets_from_shape with a negative drag",
            with_shape("shape = { box = [0.02, 2, 1] }\nfacets_from_shape = { drag = -1 }"),
            Kind::Model,
            Some(14),
            "body `panel`: facet 0: drag coefficient -1 is negative",
        ),
        (
            "facets_from_shape with a coefficient not finite",
            with_shape("shape = { box = [0.02, 2, 1] }\nfacets_from_shape = { diffuse = nan }"),
            Kind::Model,
            Some(14),
            "body `panel`: facets_from_shape.diffuse: value is not finite",
        ),
        (
            "massless leaf",
            GOOD.replace("mass = 20.0", "mass = 0").replace(
                "inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]",
                "inertia = [[0, 0, 0], [0, 0, 0], [0, 0, 0]]",
            ),
            Kind::Model,
            Some(10),
            "body `panel` is a leaf with zero mass and zero inertia",
        ),
        (
            "massless leaf, inertia defaulted",
            GOOD.replace("mass = 20.0", "mass = 0")
                .replace("inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]\n", ""),
            Kind::Model,
            Some(10),
            "zero mass and zero inertia",
        ),
        (
            "no bodies",
            "[base]\nkind = \"fixed\"\n".into(),
            Kind::Model,
            None,
            "no body",
        ),
    ];
    for (what, text, k, line, needle) in cases {
        let e = model_err(&text);
        let msg = e.to_string();
        assert_eq!(kind(&e), k, "{what}: {msg}");
        assert_eq!(e.line(), line, "{what}: {msg}");
        let prefix = match line {
            Some(l) => format!("dir/bad.toml:{l}: "),
            None => "dir/bad.toml: ".to_owned(),
        };
        assert!(msg.starts_with(&prefix), "{what}: {msg}");
        assert!(msg.contains(needle), "{what}: `{msg}` lacks `{needle}`");
        assert!(!msg.contains('\n'), "{what}: one line: {msg}");
    }
}

/// A leaf whose inertia is tiny but not zero (1e-200 on the diagonal, whose norm underflows)
/// is not a massless leaf: the model is built, and a reaction-wheel rotor this light fails in
/// the run naming its speed, not as "zero inertia".
#[test]
fn a_tiny_inertia_is_not_a_zero_one() {
    let text = GOOD.replace("mass = 20.0", "mass = 0").replace(
        "inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]",
        "inertia = [[1e-200, 0, 0], [0, 1e-200, 0], [0, 0, 1e-200]]",
    );
    let (m, _) = parse_model(&text, Path::new("ok.toml")).expect("a tiny inertia");
    assert!(m.bodies().iter().any(|b| b.inertia_com[(0, 0)] == 1e-200));
}

#[test]
fn lenient_inputs() {
    // Integers where numbers are expected, axis and rotation normalised within 1e-6,
    // defaults for `base`, `com`, `at`, `child_at`, `rotation`, inertia of a massless body.
    let text = r#"
[[body]]
name = "bus"
mass = 10
inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]

[[body]]
name = "link"
mass = 0

[[body]]
name = "tip"
mass = 1
inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]

[[hinge]]
name = "b"
parent = "link"
child = "tip"
axis = [0, 1.0000005, 0]
rotation = [1.0000005, 0, 0, 0]

[[hinge]]
name = "a"
parent = "bus"
child = "link"
axis = [0, 0, 1]
"#;
    let (m, _) = parse_model(text, Path::new("ok.toml")).unwrap();
    assert_eq!(m.base, BaseKind::Free);
    assert_eq!(m.hinge_names, ["b", "a"]);
    let j = m.joints[m.hinge_body[0]].as_ref().unwrap();
    assert!((j.axis.norm() - 1.0).abs() < 1e-15);
}

#[test]
fn read_errors() {
    let e = read_model("/nonexistent/dir/model.toml").unwrap_err();
    assert!(matches!(e, FileError::Read { .. }));
    assert!(
        e.to_string()
            .starts_with("/nonexistent/dir/model.toml: cannot read the file")
    );
    let dir = std::env::temp_dir().join(format!("satsim-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("empty.toml");
    std::fs::write(&p, "").unwrap();
    let e = read_model(&p).unwrap_err();
    assert!(matches!(e, FileError::Empty { .. }), "{e}");
    assert!(e.to_string().starts_with(&p.display().to_string()));
    let _ = std::fs::remove_dir_all(&dir);
}

fn model() -> Model {
    parse_model(GOOD, Path::new("good.toml")).unwrap().0
}

#[test]
fn good_state() {
    let m = model();
    let s = parse_state(
        r#"{"base": {"attitude": [2e-7, 0, 0, 1], "angular_velocity": [1, 2, 3], "velocity": [4, 5, 6]},
            "hinges": {"angle": [0.5], "rate": [-1], "torque": [2]}}"#,
        Path::new("s.json"),
        &m,
    )
    .unwrap();
    assert_eq!(s.q.len(), 8);
    assert!((s.q[..4].iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-15);
    assert_eq!(s.q[7], 0.5);
    assert_eq!(s.v, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, -1.0]);
    assert_eq!(s.tau, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0]);
    // No base: identity and rest; no torque: zeros.
    let s = parse_state(
        r#"{"hinges": {"angle": [0], "rate": [0]}}"#,
        Path::new("s.json"),
        &m,
    )
    .unwrap();
    assert_eq!(s, State::rest(&m));
}

#[test]
fn state_numbers_are_read_to_the_last_bit() {
    // Shortest round-trip numbers (what Python's json and `satsim` print) that a JSON
    // reader without exact float parsing reads 1 ulp off: near a gimbal lock that ulp moves
    // the accelerations by 1e-9.
    let m = model();
    for text in [
        "1.5707963267948535",
        "-1.5707963267948535",
        "3.9719863718547628",
        "3.0119351547271482",
    ] {
        let s = parse_state(
            &format!(r#"{{"hinges": {{"angle": [{text}], "rate": [{text}]}}}}"#),
            Path::new("s.json"),
            &m,
        )
        .unwrap();
        let want: f64 = text.parse().unwrap();
        assert_eq!(s.q[7].to_bits(), want.to_bits(), "angle {text}");
        assert_eq!(s.v[6].to_bits(), want.to_bits(), "rate {text}");
    }
}

#[test]
fn fixed_base_ignores_base_object() {
    let fixed = GOOD.replace("kind = \"free\"", "kind = \"fixed\"");
    let (m, _) = parse_model(&fixed, Path::new("f.toml")).unwrap();
    let s = parse_state(
        r#"{"base": {"attitude": [5, 0, 0, 0]}, "hinges": {"angle": [0.25], "rate": [1]}}"#,
        Path::new("s.json"),
        &m,
    )
    .unwrap();
    assert_eq!((s.q, s.v, s.tau), (vec![0.25], vec![1.0], vec![0.0]));
}

#[test]
fn state_error_table() {
    let m = model();
    #[derive(Debug, PartialEq)]
    enum K {
        Empty,
        Syntax,
        Schema,
        State,
    }
    let cases: Vec<(&str, &str, K, &str)> = vec![
        ("empty", "\n", K::Empty, "s/bad.json: the file is empty"),
        (
            "syntax",
            "{\n  \"hinges\": {\"angle\": [0], \"rate\": [0],}\n}",
            K::Syntax,
            "s/bad.json:2: syntax error",
        ),
        (
            "truncated",
            "{\n  \"hinges\": {\"angle\": [0],",
            K::Syntax,
            "s/bad.json:2: syntax error",
        ),
        (
            "unknown key",
            "{\n \"hinges\": {\"angle\": [0], \"rate\": [0],\n \"torques\": [0]}}",
            K::Schema,
            "s/bad.json:3: unknown key `torques`",
        ),
        (
            "missing rate",
            "{\"hinges\": {\"angle\": [0]}}",
            K::Schema,
            "s/bad.json:1: missing required key `rate`",
        ),
        (
            "wrong type",
            "{\"hinges\": {\"angle\": [\"zero\"], \"rate\": [0]}}",
            K::Schema,
            "s/bad.json:1: invalid type",
        ),
        (
            "missing hinges",
            "{}",
            K::State,
            "s/bad.json: hinges: missing",
        ),
        (
            "angle length",
            "{\"hinges\": {\"angle\": [0, 1], \"rate\": [0]}}",
            K::State,
            "s/bad.json: hinges.angle: expected 1 entries (one per hinge), got 2",
        ),
        (
            "rate length",
            "{\"hinges\": {\"angle\": [0], \"rate\": []}}",
            K::State,
            "s/bad.json: hinges.rate: expected 1 entries (one per hinge), got 0",
        ),
        (
            "torque length",
            "{\"hinges\": {\"angle\": [0], \"rate\": [0], \"torque\": [1, 2]}}",
            K::State,
            "s/bad.json: hinges.torque: expected 1 entries",
        ),
        (
            "attitude length",
            "{\"base\": {\"attitude\": [1, 0, 0]}, \"hinges\": {\"angle\": [0], \"rate\": [0]}}",
            K::State,
            "s/bad.json: base.attitude: expected 4 entries",
        ),
        (
            "attitude norm",
            "{\"base\": {\"attitude\": [1, 0, 0, 0.1]}, \"hinges\": {\"angle\": [0], \"rate\": [0]}}",
            K::State,
            "s/bad.json: base.attitude: quaternion norm",
        ),
        (
            "velocity length",
            "{\"base\": {\"velocity\": [1]}, \"hinges\": {\"angle\": [0], \"rate\": [0]}}",
            K::State,
            "s/bad.json: base.velocity: expected 3 entries",
        ),
        (
            "out-of-range number",
            "{\"hinges\": {\"angle\": [1e999], \"rate\": [0]}}",
            K::Syntax,
            "s/bad.json:1:",
        ),
    ];
    for (what, text, k, prefix) in cases {
        let e = parse_state(text, Path::new("s/bad.json"), &m).unwrap_err();
        let got = match e {
            FileError::Empty { .. } => K::Empty,
            FileError::Syntax { .. } => K::Syntax,
            FileError::Schema { .. } => K::Schema,
            FileError::State { .. } => K::State,
            _ => panic!("{what}: {e}"),
        };
        let msg = e.to_string();
        assert_eq!(got, k, "{what}: {msg}");
        assert!(msg.starts_with(prefix), "{what}: `{msg}` vs `{prefix}`");
        assert!(!msg.contains('\n'), "{what}: one line: {msg}");
    }
    // Non-finite numbers cannot be written in JSON but can reach `resolve` from TOML.
    let file = StateFile {
        base: None,
        hinges: Some(HingesStateFile {
            angle: vec![f64::NAN],
            rate: vec![0.0],
            torque: None,
        }),
    };
    let e = file.resolve(&m).unwrap_err();
    assert_eq!(e.field, "hinges.angle");
    assert!(e.message.contains("not a finite number"));
}

#[test]
fn state_from_toml_table() {
    // A scene's inline `[initial]` table uses the same keys.
    let m = model();
    let f: StateFile = toml::from_str("[hinges]\nangle = [1]\nrate = [0.5]\n").unwrap();
    let s = f.resolve(&m).unwrap();
    assert_eq!((s.q[7], s.v[6]), (1.0, 0.5));
}

#[test]
fn model_file_inside_a_larger_document() {
    // The scene reader embeds `ModelFile`: spans stay relative to the whole text.
    #[derive(Deserialize)]
    #[allow(dead_code)]
    struct Scene {
        duration: f64,
        model: ModelFile,
    }
    let text = "duration = 1.0\n\n[model]\nbody = [{ name = \"a\", mass = -1, inertia = [[1,0,0],[0,1,0],[0,0,1]] }]\n";
    let scene: Scene = toml::from_str(text).unwrap();
    let e = scene
        .model
        .build()
        .unwrap_err()
        .in_file(text, Path::new("scene.toml"));
    assert_eq!(e.to_string(), "scene.toml:4: body `a`: mass -1 is negative");
}

fn examples_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

#[test]
fn example_files_load() {
    let dir = examples_dir();
    let m = read_model(dir.join("satellite.toml")).unwrap();
    assert_eq!((m.nv(), m.n_bodies(), m.n_hinges()), (11, 6, 5));
    let s = read_state(dir.join("state.json"), &m).unwrap();
    assert_eq!(s.q.len(), 12);
    assert_eq!(s.q[7..], [0.3, -0.2, 0.1, 1.2, -1.0]);
    assert_eq!(s.v[..3], [0.001, -0.002, 0.0015]);
    assert_eq!(s.tau[6..], [0.0, 0.0, 0.0, -0.5, 0.4]);
}

#[test]
fn a_nearly_unit_attitude_is_normalised_with_a_warning() {
    let model = crate::samples::chain(2, BaseKind::Free);
    let f = |q: &str| {
        parse_state_file(
            &format!(
                "{{\"base\": {{\"attitude\": {q}}}, \"hinges\": {{\"angle\": [0], \"rate\": [0]}}}}"
            ),
            Path::new("s.json"),
        )
        .unwrap()
    };
    // Norm 1.0005: normalised, with a warning.
    let s = f("[1.0005, 0, 0, 0]");
    assert_eq!(s.warnings().len(), 1);
    assert!(s.warnings()[0].contains("normalised"));
    let st = s.resolve(&model).unwrap();
    assert_eq!(st.q[0], 1.0);
    // Rounding only: no warning.
    assert!(f("[1.0000001, 0, 0, 0]").warnings().is_empty());
    // Beyond 1e-3: refused.
    let e = f("[1.002, 0, 0, 0]").resolve(&model).unwrap_err();
    assert!(e.message.contains("within 1e-3"), "{e}");
}

/// The state file with `attitude` as given (JSON text), resolved for the two-body model.
fn attitude_of(attitude: &str) -> Result<[f64; 4], FileError> {
    let text = format!(
        "{{\n  \"base\": {{\n    \"attitude\": {attitude}\n  }},\n  \"hinges\": {{\"angle\": [0], \"rate\": [0]}}\n}}"
    );
    let s = parse_state(&text, Path::new("s.json"), &model())?;
    Ok([s.q[0], s.q[1], s.q[2], s.q[3]])
}

fn assert_close(a: [f64; 4], b: [f64; 4], what: &str) {
    let d = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-15, "{what}: {a:?} vs {b:?}");
}

#[test]
fn euler_angles_zyx_are_yaw_pitch_roll() {
    let (yaw, pitch, roll) = (30f64, -20f64, 10f64);
    let q = attitude_of(&format!(
        "{{\"euler_deg\": [{yaw}, {pitch}, {roll}], \"sequence\": \"zyx\"}}"
    ))
    .unwrap();
    // By hand: Qz(ψ) ⊗ Qy(θ) ⊗ Qx(φ), the aerospace 3-2-1 quaternion.
    let h = |d: f64| (d.to_radians() / 2.0).sin_cos();
    let ((sy, cy), (sp, cp), (sr, cr)) = (h(yaw), h(pitch), h(roll));
    let hand = [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ];
    assert_close(q, hand, "by hand");
    // nalgebra's from_euler_angles(roll, pitch, yaw) is R = Rz(yaw) Ry(pitch) Rx(roll): the
    // same rotation, with the angles in the opposite order.
    let na = nalgebra::UnitQuaternion::from_euler_angles(
        roll.to_radians(),
        pitch.to_radians(),
        yaw.to_radians(),
    );
    assert_close(q, [na.w, na.i, na.j, na.k], "nalgebra");
}

#[test]
fn euler_yaw_turns_the_body_x_axis_towards_inertial_y() {
    // A 90° yaw: the body x axis points along inertial y (body to inertial).
    let [w, x, y, z] = attitude_of(r#"{"euler_deg": [90, 0, 0], "sequence": "zyx"}"#).unwrap();
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
    assert!((q * Vec3::x() - Vec3::y()).norm() < 1e-15);
    // Intrinsic: after a 90° yaw, a 90° pitch about the turned y′ (inertial −x) tips the
    // body x axis down to inertial −z.
    let [w, x, y, z] = attitude_of(r#"{"euler_deg": [90, 90, 0], "sequence": "zyx"}"#).unwrap();
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
    assert!((q * Vec3::x() + Vec3::z()).norm() < 1e-15);
    assert!((q * Vec3::y() + Vec3::x()).norm() < 1e-15);
}

#[test]
fn proper_euler_zxz_by_hand() {
    // zxz with (α, β, γ): w = cos(β/2) cos((α+γ)/2), x = sin(β/2) cos((α−γ)/2),
    // y = sin(β/2) sin((α−γ)/2), z = cos(β/2) sin((α+γ)/2).
    let (a, b, g) = (40f64.to_radians(), 70f64.to_radians(), -25f64.to_radians());
    let q = attitude_of(r#"{"euler_deg": [40, 70, -25], "sequence": "zxz"}"#).unwrap();
    let hand = [
        (b / 2.0).cos() * ((a + g) / 2.0).cos(),
        (b / 2.0).sin() * ((a - g) / 2.0).cos(),
        (b / 2.0).sin() * ((a - g) / 2.0).sin(),
        (b / 2.0).cos() * ((a + g) / 2.0).sin(),
    ];
    assert_close(q, hand, "zxz");
}

#[test]
fn every_sequence_composes_its_three_rotations() {
    let angles: [f64; 3] = [25.0, -60.0, 110.0];
    for seq in EULER_SEQUENCES {
        let q = attitude_of(&format!(
            "{{\"euler_deg\": [25, -60, 110], \"sequence\": \"{seq}\"}}"
        ))
        .unwrap();
        // Each rotation about the body axis as turned so far: R = R1 R2 R3 (matrices).
        let axis = |c: u8| match c {
            b'x' => Vec3::x_axis(),
            b'y' => Vec3::y_axis(),
            _ => Vec3::z_axis(),
        };
        let r = seq
            .bytes()
            .zip(angles)
            .map(|(c, a)| nalgebra::Rotation3::from_axis_angle(&axis(c), f64::to_radians(a)))
            .fold(nalgebra::Rotation3::identity(), |r, x| r * x);
        let got = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q[0], q[1], q[2], q[3],
        ));
        assert!(
            (got.to_rotation_matrix().matrix() - r.matrix()).amax() < 1e-15,
            "{seq}"
        );
    }
}

#[test]
fn axis_angle_by_hand() {
    // 90° about (1, 1, 0)/√2: [cos 45°, sin 45°/√2, sin 45°/√2, 0] = [√½, ½, ½, 0].
    let q = attitude_of(r#"{"axis": [2, 2, 0], "angle_deg": 90}"#).unwrap();
    assert_close(q, [0.5f64.sqrt(), 0.5, 0.5, 0.0], "axis-angle");
    let na = nalgebra::UnitQuaternion::from_axis_angle(
        &nalgebra::Unit::new_normalize(Vec3::new(1.0, 1.0, 0.0)),
        std::f64::consts::FRAC_PI_2,
    );
    assert_close(q, [na.w, na.i, na.j, na.k], "nalgebra");
    // The same attitude three ways.
    let e = attitude_of(r#"{"euler_deg": [90, 0, 0], "sequence": "zyx"}"#).unwrap();
    let a = attitude_of(r#"{"axis": [0, 0, 1], "angle_deg": 90}"#).unwrap();
    let s = 0.5f64.sqrt();
    assert_close(e, a, "euler vs axis");
    assert_close(e, [s, 0.0, 0.0, s], "euler vs quaternion");
}

#[test]
fn attitude_forms_from_toml() {
    // A scene's inline `[initial]` table takes the same forms.
    let m = model();
    let f: StateFile = toml::from_str(
        "[base]\nattitude = { axis = [0, 0, 1], angle_deg = 180 }\n[hinges]\nangle = [0]\nrate = [0]\n",
    )
    .unwrap();
    let q = f.resolve(&m).unwrap().q;
    assert!(q[0].abs() < 1e-16 && (q[3] - 1.0).abs() < 1e-16, "{q:?}");
    assert!(f.warnings().is_empty());
    // An error names the line of the attitude, here in a larger document.
    #[derive(Deserialize)]
    #[allow(dead_code)]
    struct Scene {
        duration: f64,
        initial: StateFile,
    }
    let text =
        "duration = 1.0\n\n[initial.base]\nattitude = { euler_deg = [1, 2], sequence = \"zyx\" }\n";
    let Err(e) = toml::from_str::<Scene>(text) else {
        panic!("accepted")
    };
    let line = line_of(text, e.span().expect("span").start);
    assert_eq!(line, 4, "{e}");
    assert!(e.message().contains("expected 3 numbers"), "{e}");
}

#[test]
fn attitude_form_errors_name_file_and_line() {
    // The attitude object opens on line 3 and closes on line 3 (one line): errors there.
    let cases = [
        (
            r#"{"euler_deg": [1, 2, 3], "sequence": "zzx"}"#,
            "unknown Euler sequence \"zzx\"",
        ),
        (
            r#"{"euler_deg": [1, 2, 3], "sequence": "ZYX"}"#,
            "unknown Euler sequence \"ZYX\"",
        ),
        (
            r#"{"euler_deg": [1, 2, 3, 4], "sequence": "zyx"}"#,
            "`euler_deg`: expected 3 numbers",
        ),
        (
            r#"{"euler_deg": [1, 2], "sequence": "zyx"}"#,
            "`euler_deg`: expected 3 numbers",
        ),
        (
            r#"{"euler_deg": [1, 2, 3]}"#,
            "`euler_deg` needs `sequence`",
        ),
        (r#"{"sequence": "zyx"}"#, "`sequence` needs `euler_deg`"),
        (r#"{"axis": [0, 0, 0], "angle_deg": 10}"#, "`axis` is zero"),
        (
            r#"{"axis": [0, 0, 1, 0], "angle_deg": 10}"#,
            "`axis`: expected 3 numbers",
        ),
        (r#"{"axis": [0, 0, 1]}"#, "`axis` needs `angle_deg`"),
        (r#"{"angle_deg": 10}"#, "`angle_deg` needs `axis`"),
        (
            r#"{"axis": [0, 0, 1], "angle_deg": 10, "euler_deg": [1, 2, 3]}"#,
            "give either `euler_deg` and `sequence`, or `axis` and `angle_deg`",
        ),
        (r#"{"axis": [0, 0, 1], "angle": 10}"#, "unknown key `angle`"),
        (r#""identity""#, "invalid type"),
    ];
    for (attitude, message) in cases {
        let e = attitude_of(attitude).unwrap_err();
        assert!(matches!(e, FileError::Schema { .. }), "{attitude}: {e}");
        let shown = e.to_string();
        assert!(shown.starts_with("s.json:3: "), "{attitude}: {shown}");
        assert!(shown.contains(message), "{attitude}: {shown}");
    }
}

#[test]
fn the_quaternion_form_keeps_its_checks() {
    // Near-unit: normalised with a warning; the other forms never warn.
    let q = attitude_of("[1.0005, 0, 0, 0]").unwrap();
    assert_eq!(q, [1.0, 0.0, 0.0, 0.0]);
    let e = attitude_of("[1, 0, 0]").unwrap_err().to_string();
    assert_eq!(
        e,
        "s.json: base.attitude: expected 4 entries (a quaternion [w, x, y, z]), got 3"
    );
    let e = attitude_of("[1.002, 0, 0, 0]").unwrap_err().to_string();
    assert!(
        e.starts_with("s.json: base.attitude: quaternion norm"),
        "{e}"
    );
}

#[test]
fn names_that_become_columns_are_letters_digits_and_underscores() {
    // A comma, space, quote or newline in a body or hinge name would break the CSV files'
    // rows: refused at the name's line, the name shown as written.
    for (from, to, line, key) in [
        ("name = \"h\"", "name = \"a,b\"", 15, "hinge.name"),
        ("name = \"h\"", "name = \"a\\nb\"", 15, "hinge.name"),
        (
            "name = \"panel\"",
            "name = \"solar panel\"",
            10,
            "body.name",
        ),
        ("name = \"bus\"", "name = \"\"", 5, "body.name"),
    ] {
        let text = GOOD.replacen(from, to, 1);
        let e = parse_model(&text, Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&format!(
                "m.toml:{line}: `{key}` must be letters, digits and `_`"
            )),
            "{to}: {e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
    }
    // The flexible reader reads the same names.
    let text = GOOD.replacen("name = \"h\"", "name = \"h;1\"", 1);
    let e = parse_flex_model(&text, Path::new("m.toml")).unwrap_err();
    assert!(e.to_string().starts_with("m.toml:15: `hinge.name`"), "{e}");
}

#[test]
fn rates_beyond_2_rad_per_s_warn_as_angles_beyond_a_turn_do() {
    let f = |w: &str, rate: &str| {
        parse_state_file(
            &format!(
                "{{\"base\": {{\"angular_velocity\": {w}}}, \"hinges\": {{\"angle\": [0], \"rate\": [{rate}]}}}}"
            ),
            Path::new("s.json"),
        )
        .unwrap()
        .warnings()
    };
    assert!(f("[0.1, -2.0, 1.0]", "2.0").is_empty());
    assert_eq!(
        f("[5, 5, 5]", "0"),
        [
            "base.angular_velocity: entry 0 is 5 rad/s, beyond ±2 rad/s: rates are in rad/s (for 5 deg/s write 0.087266)"
        ]
    );
    // A huge value is written short, not in 301 digits.
    let w = f("[1e300, 0, 0]", "0");
    assert!(
        w[0].starts_with("base.angular_velocity: entry 0 is 1e300 rad/s, beyond ±2 rad/s"),
        "{w:?}"
    );
    let w = f("[0, 0, 0]", "-90");
    assert_eq!(w.len(), 1);
    assert!(
        w[0].starts_with("hinges.rate: entry 0 is -90 rad/s, beyond ±2 rad/s"),
        "{w:?}"
    );
}
