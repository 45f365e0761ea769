//! Where each part of the state lives in `x`.

use std::ops::Range;

/// Where each part of the state lives in `x`: `[attitude (4), angles (n), ω (3), v (3),
/// rates (n), η (m), η̇ (m), the effects' own states]` for a free base, `[angles, rates, η,
/// η̇, ...]` for a fixed one (`η`: the flexible bodies' elastic coordinates, none in a rigid
/// tree). The right-hand side relies on this order: `[ω; v; rates]` is the rigid tree's
/// velocity vector as it stands, and so is the head of its derivative.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StateLayout {
    /// Free-floating root.
    pub free: bool,
    /// Number of the model's hinges.
    pub n_hinges: usize,
    /// Attitude quaternion (empty for a fixed base).
    pub attitude: Range<usize>,
    /// Hinge angles, file order.
    pub angles: Range<usize>,
    /// Root angular velocity, root axes (empty for a fixed base).
    pub omega: Range<usize>,
    /// Root origin velocity, root axes (empty for a fixed base).
    pub velocity: Range<usize>,
    /// Hinge rates, file order.
    pub rates: Range<usize>,
    /// Elastic coordinates `η` of the flexible bodies (bodies in the tree's depth-first
    /// order, modes from 1 within a body; empty in a rigid tree).
    pub eta: Range<usize>,
    /// Their rates `η̇`, same order.
    pub etadot: Range<usize>,
    /// Each enabled effect's own states, by name, in the effects' order.
    pub effects: Vec<(String, Range<usize>)>,
    /// Total length of the state.
    pub len: usize,
}

impl StateLayout {
    pub(super) fn new(free: bool, n: usize, m: usize, own: &[(String, usize)]) -> Self {
        let b = if free { 4 } else { 0 };
        let attitude = 0..b;
        let angles = b..b + n;
        let w = if free { 3 } else { 0 };
        let omega = angles.end..angles.end + w;
        let velocity = omega.end..omega.end + w;
        let rates = velocity.end..velocity.end + n;
        let eta = rates.end..rates.end + m;
        let etadot = eta.end..eta.end + m;
        let mut at = etadot.end;
        let effects = own
            .iter()
            .map(|(name, k)| {
                let r = at..at + k;
                at += k;
                (name.clone(), r)
            })
            .collect();
        Self {
            free,
            n_hinges: n,
            attitude,
            angles,
            omega,
            velocity,
            rates,
            eta,
            etadot,
            effects,
            len: at,
        }
    }
    /// The range of effect `name`'s states, if it is enabled and has any.
    pub fn effect(&self, name: &str) -> Option<Range<usize>> {
        self.effects
            .iter()
            .find(|(n, r)| n == name && !r.is_empty())
            .map(|(_, r)| r.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::StateLayout;

    #[test]
    fn the_velocity_vector_is_contiguous_after_the_attitude_and_angles() {
        let l = StateLayout::new(true, 5, 0, &[("reaction_wheels".into(), 3)]);
        assert_eq!((l.attitude.clone(), l.angles.clone()), (0..4, 4..9));
        assert_eq!(
            (l.omega.end, l.velocity.end),
            (l.velocity.start, l.rates.start)
        );
        assert_eq!(l.rates.end, l.effect("reaction_wheels").unwrap().start);
        let f = StateLayout::new(false, 2, 0, &[]);
        assert_eq!((f.angles, f.rates, f.len), (0..2, 2..4, 4));
        let e = StateLayout::new(true, 2, 3, &[("orbit".into(), 6)]);
        assert_eq!(
            (e.rates.clone(), e.eta.clone(), e.etadot.clone()),
            (12..14, 14..17, 17..20)
        );
        assert_eq!(e.effect("orbit"), Some(20..26));
    }
}
