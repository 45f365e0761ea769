//! How far a flexible body is bent, against the size its modal model is meant for: a beam's
//! tip against its length, a modes file's watched nodes against their distance from the
//! body's frame. What a run watches (`satsim run`'s warning, a campaign's
//! `peak_deflection_<body>` column, a failed solve's message) and what finite differences in
//! `η` step by ([`FlexModel::modal_scale`]).

use super::model::{FlexModel, WatchPoint};
use crate::spatial::Vec3;

impl FlexModel {
    /// The deflection of body `i`'s beam tip along `bend` (m) in `q`; `None` unless its
    /// modes are a beam's.
    pub fn tip_deflection(&self, i: usize, q: &[f64]) -> Option<f64> {
        self.tip_of(i, &q[self.rigid.nq()..])
    }
    /// [`Self::tip_deflection`] from the elastic coordinates `eta` alone (all of them, in
    /// order).
    pub fn tip_of(&self, i: usize, eta: &[f64]) -> Option<f64> {
        self.beams[i].as_ref()?;
        let eta = &eta[self.offset[i]..][..self.modes[i]];
        Some(self.tips[i].iter().zip(eta).map(|(p, e)| p * e).sum())
    }
    /// How far body `i` is bent in `eta` (all elastic coordinates, in order), against the
    /// size the modal model is meant for: for a beam, its tip's deflection along `bend`
    /// against its length; for given modes, the watched point ([`WatchPoint`], off the
    /// frame's origin) displaced most for its distance from the frame's origin, that
    /// displacement's size against the distance. `None` for a rigid body and for given modes
    /// without such a point.
    pub fn deflection_of(&self, i: usize, eta: &[f64]) -> Option<Deflection> {
        if let Some(beam) = &self.beams[i] {
            return Some(Deflection {
                offset: self.tip_of(i, eta)?,
                length: beam.length,
                point: None,
            });
        }
        let eta = &eta[self.offset[i]..][..self.modes[i]];
        let mut worst: Option<Deflection> = None;
        for (k, p) in self.watch[i].iter().enumerate() {
            let d: Vec3 = p.translation.iter().zip(eta).map(|(t, e)| t * *e).sum();
            let here = Deflection {
                offset: d.norm(),
                length: p.at.norm(),
                point: Some(k),
            };
            if worst.is_none_or(|w| here.fraction() > w.fraction()) {
                worst = Some(here);
            }
        }
        worst
    }
    /// The size of elastic coordinate `e` (from 0, all the elastic coordinates in order)
    /// that bends its body by its whole size: `1 / max(|φₖ(p)| / ℓ + |ψₖ(p)|)` over the
    /// points [`Self::deflection_of`] watches (a beam's tip, `ℓ` its length, `ψₖ` its slope;
    /// a modes file's watched nodes, `ℓ` their distance from the frame's origin, translation
    /// only). A scale for finite differences in `ηₖ`: its unit, `√kg m`, is the body's size
    /// only for a body of about a kilogram (a 0.4 g strip of 0.2 m is bent past its length by
    /// `ηₖ = 2e-3`). `None` where nothing is watched or the mode moves no watched point.
    pub fn modal_scale(&self, e: usize) -> Option<f64> {
        let (i, k) = self.mode_of(e)?;
        let k = k - 1;
        let largest = if let Some(beam) = &self.beams[i] {
            let tip = beam.node(&(beam.root + beam.axis * beam.length));
            tip.phi[k].norm() / beam.length + tip.psi[k].norm()
        } else {
            self.watch[i]
                .iter()
                .filter(|p| p.at.norm() > 0.0)
                .map(|p| p.translation[k].norm() / p.at.norm())
                .fold(0.0, f64::max)
        };
        (largest > 0.0 && largest.is_finite()).then(|| 1.0 / largest)
    }

    /// Whether [`Self::deflection_of`] watches body `i`: a beam, or given modes with a
    /// point off the frame's origin.
    pub fn watched(&self, i: usize) -> bool {
        self.beams[i].is_some() || !self.watch[i].is_empty()
    }
    /// The points of body `i` that [`Self::deflection_of`] watches, for given modes (a
    /// [`Deflection`]'s `point` indexes them); empty for a beam, whose tip is watched.
    pub fn watch_points(&self, i: usize) -> &[WatchPoint] {
        &self.watch[i]
    }
    /// The bodies bent in `q` by more than [`SMALL_DEFLECTION`] of their size
    /// ([`Self::deflection_of`]), the largest first: deflections beyond what a modal model
    /// holds. Empty where every deflection is small (and for given modes with no watched
    /// point). A solve that fails on such a state fails where the model does not hold: with
    /// `stiffening` the inertia is right to second order only, and on a bus with two 2 m
    /// beams the moment about a beam's own axis (zero undeformed) is already `−2.6e-5` of
    /// the trace at a tenth of the length.
    pub fn large_deflections(&self, q: &[f64]) -> Vec<LargeDeflection> {
        let eta = &q[self.rigid.nq()..];
        let mut out: Vec<LargeDeflection> = (0..self.rigid.n_bodies())
            .filter_map(|i| {
                let d = self.deflection_of(i, eta)?;
                (d.fraction() > SMALL_DEFLECTION).then(|| LargeDeflection {
                    body: i,
                    tip: d.offset,
                    length: d.length,
                    point: d.point,
                    eta: eta[self.offset[i]..][..self.modes[i]].to_vec(),
                })
            })
            .collect();
        let size = |d: &LargeDeflection| d.tip.abs() / d.length;
        out.sort_by(|a, b| size(b).total_cmp(&size(a)));
        out
    }
}

/// The deflection, as a fraction of a beam's length (or of a watched point's distance from
/// its body's frame), beyond which [`FlexModel::large_deflections`] calls it large: a modal
/// model (the floating frame's linear deformation, with `stiffening` its second-order
/// foreshortening) is meant for deflections of a few per cent of the length.
pub const SMALL_DEFLECTION: f64 = 0.1;

/// How far a flexible body is bent ([`FlexModel::deflection_of`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deflection {
    /// A beam's tip deflection along `bend` (signed), or the size of a watched point's
    /// displacement (m).
    pub offset: f64,
    /// The beam's length, or the watched point's distance from the body frame's origin (m).
    pub length: f64,
    /// The watched point ([`FlexModel::watch_points`]); `None` for a beam's tip.
    pub point: Option<usize>,
}

impl Deflection {
    /// The deflection as a fraction of the length: past [`SMALL_DEFLECTION`], beyond the
    /// modal model.
    pub fn fraction(&self) -> f64 {
        self.offset.abs() / self.length
    }
}

/// A flexible body deflected beyond what its modal model holds
/// ([`FlexModel::large_deflections`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LargeDeflection {
    /// The body.
    pub body: usize,
    /// Its beam's tip deflection along `bend`, or its watched point's displacement (m).
    pub tip: f64,
    /// Its beam's length, or the watched point's distance from the frame's origin (m).
    pub length: f64,
    /// The watched point ([`FlexModel::watch_points`]); `None` for a beam's tip.
    pub point: Option<usize>,
    /// Its elastic coordinates.
    pub eta: Vec<f64>,
}
