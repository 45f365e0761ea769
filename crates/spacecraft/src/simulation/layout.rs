//! Where each part of the state lives in `x`.

use std::ops::Range;

/// Where each part of the state lives in `x`: `[attitude (4), angles (n), ω (3), v (3),
/// rates (n), the effects' own states]` for a free base, `[angles, rates, ...]` for a fixed
/// one. The right-hand side relies on this order: `[ω; v; rates]` is the tree's velocity
/// vector as it stands, and so is the head of its derivative.
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
    /// Each enabled effect's own states, by name, in the effects' order.
    pub effects: Vec<(String, Range<usize>)>,
    /// Total length of the state.
    pub len: usize,
}

impl StateLayout {
    pub(super) fn new(free: bool, n: usize, own: &[(String, usize)]) -> Self {
        let b = if free { 4 } else { 0 };
        let attitude = 0..b;
        let angles = b..b + n;
        let w = if free { 3 } else { 0 };
        let omega = angles.end..angles.end + w;
        let velocity = omega.end..omega.end + w;
        let rates = velocity.end..velocity.end + n;
        let mut at = rates.end;
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
        let l = StateLayout::new(true, 5, &[("reaction_wheels".into(), 3)]);
        assert_eq!((l.attitude.clone(), l.angles.clone()), (0..4, 4..9));
        assert_eq!(
            (l.omega.end, l.velocity.end),
            (l.velocity.start, l.rates.start)
        );
        assert_eq!(l.rates.end, l.effect("reaction_wheels").unwrap().start);
        let f = StateLayout::new(false, 2, &[]);
        assert_eq!((f.angles, f.rates, f.len), (0..2, 2..4, 4));
    }
}
