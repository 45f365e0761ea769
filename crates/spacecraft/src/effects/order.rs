//! The order in which a simulation visits its effects: a stable topological sort of the
//! dependencies they declare ([`Effect::after`], [`Effect::before`]).
//!
//! Stable: among the effects whose dependencies have all run, the one given first runs
//! first, so that effects without dependencies keep the order they were given in (a scene
//! gives them in its registry's order, [`super::Registry`]). Kahn's algorithm, O(n²) in the
//! number of effects (a handful), run once when a simulation is built.

use super::Effect;

/// The order to visit `effects` in (indices into `effects`), or a message naming a missing
/// dependency or the effects on a cycle.
///
/// ```
/// use satsim_spacecraft::effects::{AttitudeControl, Effect, ReactionWheels, Target, order};
/// use nalgebra::UnitQuaternion;
/// let control = AttitudeControl::new(Target::Inertial(UnitQuaternion::identity()), 1.0, 1.0);
/// let effects: Vec<Box<dyn Effect>> =
///     vec![Box::new(ReactionWheels::new(Vec::new())), Box::new(control)];
/// // Attitude control runs before the wheels it commands.
/// assert_eq!(order::run_order(&effects).unwrap(), vec![1, 0]);
/// ```
pub fn run_order(effects: &[Box<dyn Effect>]) -> Result<Vec<usize>, String> {
    let n = effects.len();
    let index = |name: &str| effects.iter().position(|e| e.name() == name);
    // before[i][j]: effect i must run before effect j.
    let mut edges = vec![false; n * n];
    for (i, e) in effects.iter().enumerate() {
        for d in e.after() {
            let j = index(d).ok_or_else(|| {
                format!(
                    "effects.{} runs after `{d}`, which is not enabled (enable [effects.{d}])",
                    e.name()
                )
            })?;
            edges[j * n + i] = true;
        }
        for d in e.before() {
            let j = index(d).ok_or_else(|| {
                format!(
                    "effects.{} runs before `{d}`, which is not enabled (enable [effects.{d}])",
                    e.name()
                )
            })?;
            edges[i * n + j] = true;
        }
    }
    let mut done = vec![false; n];
    let mut order = Vec::with_capacity(n);
    while order.len() < n {
        let ready = (0..n).find(|&j| !done[j] && (0..n).all(|i| done[i] || !edges[i * n + j]));
        match ready {
            Some(j) => {
                done[j] = true;
                order.push(j);
            }
            None => {
                let stuck: Vec<&str> = (0..n)
                    .filter(|&j| !done[j])
                    .map(|j| effects[j].name())
                    .collect();
                return Err(format!(
                    "the effects {} depend on each other in a cycle (see their `after`/`before`)",
                    stuck.join(", ")
                ));
            }
        }
    }
    Ok(order)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::{Context, Forces};
    use satsim_integrate::SystemError;

    struct Named(
        &'static str,
        &'static [&'static str],
        &'static [&'static str],
    );
    impl Effect for Named {
        fn name(&self) -> &str {
            self.0
        }
        fn after(&self) -> &[&str] {
            self.1
        }
        fn before(&self) -> &[&str] {
            self.2
        }
        fn apply(
            &mut self,
            _: &Context,
            _: &mut Forces,
            _: &[f64],
            _: &mut [f64],
        ) -> Result<(), SystemError> {
            Ok(())
        }
    }

    fn boxed(list: Vec<Named>) -> Vec<Box<dyn Effect>> {
        list.into_iter()
            .map(|e| Box::new(e) as Box<dyn Effect>)
            .collect()
    }

    #[test]
    fn independent_effects_keep_their_order_and_dependencies_move_them() {
        let e = boxed(vec![
            Named("a", &["c"], &[]),
            Named("b", &[], &[]),
            Named("c", &[], &[]),
            Named("d", &[], &["b"]),
        ]);
        // c before a, d before b; otherwise the given order.
        assert_eq!(run_order(&e).unwrap(), vec![2, 0, 3, 1]);
        let none = boxed(vec![Named("x", &[], &[]), Named("y", &[], &[])]);
        assert_eq!(run_order(&none).unwrap(), vec![0, 1]);
    }

    #[test]
    fn missing_dependencies_and_cycles_are_errors() {
        let missing = boxed(vec![Named("a", &["nope"], &[])]);
        let e = run_order(&missing).unwrap_err();
        assert!(e.contains("effects.a runs after `nope`"), "{e}");
        let cycle = boxed(vec![
            Named("a", &["b"], &[]),
            Named("b", &[], &["a"]),
            Named("c", &[], &["b"]),
        ]);
        // a after b and b before a agree; c before b, fine: no cycle.
        assert_eq!(run_order(&cycle).unwrap(), vec![2, 1, 0]);
        let cycle = boxed(vec![Named("a", &["b"], &[]), Named("b", &["a"], &[])]);
        let e = run_order(&cycle).unwrap_err();
        assert!(e.contains("a, b") && e.contains("cycle"), "{e}");
    }
}
