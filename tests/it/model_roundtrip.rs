//! Round trip through the model file (proptest, in CI): random valid trees (branching, up to
//! 40 bodies, massless gimbal links, free and fixed roots, random axes, offsets, rotations
//! and armatures) written in the model-file TOML format and read back are the same model
//! (names, masses, centres of mass, inertias, offsets, armatures bit for bit; the axes,
//! renormalised by the reader, to 1e-15; the fixed rotations bit for bit) and give the same
//! dynamics (ABA and CRBA to 1e-12).

use proptest::prelude::*;
use satsim::tree::aba::aba;
use satsim::tree::samples::{SplitMix, random_tree};
use satsim::tree::{BaseKind, Data, Model, crba, parse_model};
use std::fmt::Write;
use std::path::Path;

/// `{}` prints the shortest text that reads back to the same f64.
fn v3(v: &nalgebra::Vector3<f64>) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

/// The model in the model-file format.
fn to_toml(m: &Model) -> String {
    let mut s = String::new();
    let kind = match m.base() {
        BaseKind::Free => "free",
        BaseKind::Fixed => "fixed",
    };
    writeln!(s, "[base]\nkind = \"{kind}\"").unwrap();
    for b in m.bodies() {
        let i = b.inertia_com();
        writeln!(
            s,
            "\n[[body]]\nname = \"{}\"\nmass = {}\ncom = {}\ninertia = [[{}, {}, {}], [{}, {}, {}], [{}, {}, {}]]",
            b.name(),
            b.mass(),
            v3(b.com()),
            i[(0, 0)],
            i[(0, 1)],
            i[(0, 2)],
            i[(1, 0)],
            i[(1, 1)],
            i[(1, 2)],
            i[(2, 0)],
            i[(2, 1)],
            i[(2, 2)]
        )
        .unwrap();
        if let Some(shape) = b.shape() {
            let at = shape
                .at
                .map_or(String::new(), |a| format!(", at = {}", v3(&a)));
            writeln!(s, "shape = {{ box = {}{at} }}", v3(&shape.size)).unwrap();
        }
        // Every facet explicitly (those of `facets_from_shape` too), its rectangle by
        // `size` and `edge`.
        let facets: Vec<String> = b
            .facets()
            .iter()
            .map(|f| {
                let (a, c) = (f.edges[0].norm(), f.edges[1].norm());
                format!(
                    "{{ area = {}, normal = {}, at = {}, specular = {}, diffuse = {}, drag = {}, size = [{a}, {c}], edge = {} }}",
                    f.area,
                    v3(&f.normal),
                    v3(&f.at),
                    f.specular,
                    f.diffuse,
                    f.drag,
                    v3(&(f.edges[0] / a))
                )
            })
            .collect();
        if !facets.is_empty() {
            writeln!(s, "facets = [{}]", facets.join(", ")).unwrap();
        }
    }
    for (k, name) in m.hinge_names().iter().enumerate() {
        let i = m.hinge_body()[k];
        let j = m.joint(i).unwrap();
        let p = m.parent()[i].unwrap();
        let q = j.rotation();
        writeln!(
            s,
            "\n[[hinge]]\nname = \"{name}\"\nparent = \"{}\"\nchild = \"{}\"\naxis = {}\nat = {}\nchild_at = {}\nrotation = [{}, {}, {}, {}]\narmature = {}",
            m.bodies()[p].name(),
            m.bodies()[i].name(),
            v3(j.axis()),
            v3(j.at()),
            v3(j.child_at()),
            q.w,
            q.i,
            q.j,
            q.k,
            j.armature()
        )
        .unwrap();
    }
    s
}

fn random_model(n: usize, free: bool, massless: bool, seed: u64) -> Model {
    let base = if free {
        BaseKind::Free
    } else {
        BaseKind::Fixed
    };
    let mut builder = random_tree(n, base, massless, seed).to_builder();
    let mut rng = SplitMix(seed ^ 0xa7a7);
    for h in builder.hinges_mut() {
        if rng.next_f64() < 0.5 {
            h.armature = rng.range(0.0, 0.1);
        }
    }
    builder.build().expect("armature keeps a valid tree valid")
}

fn check(n: usize, free: bool, massless: bool, seed: u64) -> Result<(), TestCaseError> {
    let m = random_model(n, free, massless, seed);
    let text = to_toml(&m);
    let (r, _) = parse_model(&text, Path::new("roundtrip.toml"))
        .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
    prop_assert_eq!(r.hinge_names(), m.hinge_names());
    prop_assert_eq!(r.parent(), m.parent());
    prop_assert_eq!(r.hinge_body(), m.hinge_body());
    for (a, b) in r.bodies().iter().zip(m.bodies()) {
        prop_assert_eq!(a.name(), b.name());
        prop_assert_eq!(a.mass(), b.mass());
        prop_assert_eq!(a.com(), b.com());
        prop_assert_eq!(a.inertia_com(), b.inertia_com());
    }
    prop_assert!(r.joint(0).is_none() && m.joint(0).is_none());
    for i in 1..m.n_bodies() {
        let (Some(a), Some(b)) = (r.joint(i), m.joint(i)) else {
            return Err(TestCaseError::fail(format!("body {i} has no joint")));
        };
        prop_assert_eq!((a.hinge(), a.dof()), (b.hinge(), b.dof()));
        prop_assert_eq!(
            (a.at(), a.child_at(), a.armature()),
            (b.at(), b.child_at(), b.armature())
        );
        // The reader normalises the axis: the last bit may move.
        prop_assert!(
            (a.axis() - b.axis()).amax() <= 1e-15,
            "axis {:e}",
            (a.axis() - b.axis()).amax()
        );
        // The writer writes the rotation as it was given: the same quaternion, the same
        // matrix, bit for bit.
        prop_assert_eq!(a.rotation(), b.rotation());
        prop_assert_eq!(a.rot0(), b.rot0());
    }
    // Same dynamics.
    let mut rng = SplitMix(seed ^ 0x5eed);
    let mut q = m.neutral();
    for x in &mut q[m.base_nq()..] {
        *x = rng.range(-3.0, 3.0);
    }
    let v: Vec<f64> = (0..m.nv()).map(|_| rng.range(-1.0, 1.0)).collect();
    let tau: Vec<f64> = (0..m.nv()).map(|_| rng.range(-1.0, 1.0)).collect();
    let (mut d1, mut d2) = (Data::new(&m), Data::new(&r));
    let a1 = aba(&m, &mut d1, &q, &v, &tau, None).unwrap().clone();
    let a2 = aba(&r, &mut d2, &q, &v, &tau, None).unwrap().clone();
    let rel = (&a1 - &a2).amax() / a1.amax().max(1.0);
    prop_assert!(rel <= 1e-12, "ABA differs by {:e}", rel);
    let m1 = crba(&m, &mut d1, &q).unwrap().clone();
    let m2 = crba(&r, &mut d2, &q).unwrap().clone();
    let rel = (&m1 - &m2).amax() / m1.amax().max(1.0);
    prop_assert!(rel <= 1e-12, "CRBA differs by {:e}", rel);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_models_round_trip_through_the_model_file(
        n in 1usize..=40,
        free in any::<bool>(),
        massless in any::<bool>(),
        seed in any::<u64>(),
    ) {
        check(n, free, massless, seed)?;
    }
}

/// The example satellite (massless links, armature-free, facets from its shapes)
/// round-trips too.
#[test]
fn the_example_satellite_round_trips() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/satellite.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let (m, _) = parse_model(&text, &path).unwrap();
    let (r, _) = parse_model(&to_toml(&m), Path::new("x.toml")).unwrap();
    assert_eq!(r, m);
}
