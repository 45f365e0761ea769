use nalgebra::{Matrix3, Quaternion};
use satsim_tree::spatial::Vec3;
use satsim_tree::*;
use std::path::Path;

fn v3(v: &toml::Value) -> Vec3 {
    let a = v.as_array().unwrap();
    Vec3::new(f(&a[0]), f(&a[1]), f(&a[2]))
}
fn f(v: &toml::Value) -> f64 {
    v.as_float().or(v.as_integer().map(|i| i as f64)).unwrap()
}

fn load(name: &str) -> (Model, Vec<f64>, Vec<f64>, Vec<f64>, serde_json::Value) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/pinocchio");
    let t: toml::Value =
        toml::from_str(&std::fs::read_to_string(dir.join(format!("{name}.model.toml"))).unwrap())
            .unwrap();
    let base = match t
        .get("base")
        .and_then(|b| b.get("kind"))
        .and_then(|k| k.as_str())
    {
        Some("fixed") => BaseKind::Fixed,
        _ => BaseKind::Free,
    };
    let mut b = ModelBuilder::new(base);
    for body in t["body"].as_array().unwrap() {
        let i = body
            .get("inertia")
            .map(|i| {
                let r: Vec<Vec3> = i.as_array().unwrap().iter().map(v3).collect();
                Matrix3::from_rows(&[r[0].transpose(), r[1].transpose(), r[2].transpose()])
            })
            .unwrap_or_else(Matrix3::zeros);
        let mut bb = Body::new(body["name"].as_str().unwrap(), f(&body["mass"]), i);
        if let Some(c) = body.get("com") {
            bb = bb.with_com(v3(c));
        }
        b.push_body(bb);
    }
    for h in t
        .get("hinge")
        .and_then(|x| x.as_array())
        .cloned()
        .unwrap_or_default()
        .iter()
    {
        let mut hh = Hinge::revolute(
            h["name"].as_str().unwrap(),
            h["parent"].as_str().unwrap(),
            h["child"].as_str().unwrap(),
            v3(&h["axis"]),
        );
        if let Some(x) = h.get("at") {
            hh = hh.at(v3(x));
        }
        if let Some(x) = h.get("child_at") {
            hh = hh.child_at(v3(x));
        }
        if let Some(x) = h.get("rotation") {
            let a = x.as_array().unwrap();
            hh = hh.rotation(Quaternion::new(f(&a[0]), f(&a[1]), f(&a[2]), f(&a[3])));
        }
        b.push_hinge(hh);
    }
    let model = b.build().unwrap();
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{name}.state.json"))).unwrap(),
    )
    .unwrap();
    let arr = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .map(|a| a.iter().map(|x| x.as_f64().unwrap()).collect())
            .unwrap_or_default()
    };
    let mut q = model.neutral();
    let mut v = vec![0.0; model.nv()];
    let mut tau = vec![0.0; model.nv()];
    let nb = model.base_nv();
    let nqb = model.base_nq();
    if nb == 6 {
        if let Some(base) = s.get("base") {
            if let Some(a) = base.get("attitude") {
                q[..4].copy_from_slice(&arr(a));
            }
            if let Some(a) = base.get("angular_velocity") {
                v[..3].copy_from_slice(&arr(a));
            }
            if let Some(a) = base.get("velocity") {
                v[3..6].copy_from_slice(&arr(a));
            }
        }
    }
    let h = &s["hinges"];
    q[nqb..].copy_from_slice(&arr(&h["angle"]));
    v[nb..].copy_from_slice(&arr(&h["rate"]));
    if let Some(t) = h.get("torque") {
        tau[nb..].copy_from_slice(&arr(t));
    }
    let e: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{name}.expected.json"))).unwrap(),
    )
    .unwrap();
    (model, q, v, tau, e)
}

#[test]
fn quick_against_pinocchio() {
    for name in [
        "single_body_free",
        "satellite",
        "satellite_rotated",
        "chain_fixed",
        "tree_free",
        "wheel",
        "tree_free_big",
    ] {
        let (model, q, v, tau, e) = load(name);
        let mut d = Data::new(&model);
        let m = crba(&model, &mut d, &q).unwrap().clone();
        let em: Vec<Vec<f64>> = serde_json::from_value(e["mass_matrix"].clone()).unwrap();
        let scale = em.iter().flatten().fold(1.0f64, |a, x| a.max(x.abs()));
        let mut err = 0.0f64;
        for i in 0..model.nv() {
            for j in 0..model.nv() {
                err = err.max((m[(i, j)] - em[i][j]).abs());
            }
        }
        let b = bias(&model, &mut d, &q, &v, None).unwrap().clone();
        let eb: Vec<f64> = serde_json::from_value(e["bias"].clone()).unwrap();
        let berr = b
            .iter()
            .zip(&eb)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let a = aba(&model, &mut d, &q, &v, &tau, None).unwrap().clone();
        let a2 = crba_cholesky(&model, &mut d, &q, &v, &tau, None)
            .unwrap()
            .clone();
        let ea: Vec<f64> = serde_json::from_value(e["acceleration"].clone()).unwrap();
        let aerr = a
            .iter()
            .zip(&ea)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let a2err = a2
            .iter()
            .zip(&ea)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let ke = kinetic_energy(&model, &mut d, &q, &v).unwrap();
        println!(
            "{name}: M {:.2e} (scale {scale:.1e}) bias {berr:.2e} aba {aerr:.2e} chol {a2err:.2e} ke {:.2e}",
            err,
            (ke - e["kinetic_energy"].as_f64().unwrap()).abs()
        );
    }
}
