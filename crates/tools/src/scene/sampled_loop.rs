//! Whether a sampled attitude law (`[effects.attitude_control]` with a `period`) is stable at
//! its period: the zero-order-hold loop over one period, on the scene's linear motions at
//! its initial state (the linearisation of [`super::step_limit`]). An unstable one is the
//! design's, not the integrator's, so the scene reader warns of it and runs it.

use nalgebra::{Complex, DMatrix, Schur};
use satsim_tree::flexible::FlexModel;

use super::step_limit::{AttitudeGains, HingeGains, diagonal_matrices, last_stable, plant};

/// How a sampled attitude law fares at its period ([`sampled_attitude`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SampledLoop {
    /// The largest `|z|` of the closed loop's eigenvalues over one period: above 1 a motion
    /// grows by that factor a sample.
    pub growth: f64,
    /// Where the loop is unstable at its period: the longest period below it at which it is
    /// stable (the stable periods found from zero up, to round-off), `None` where it is
    /// stable at its own.
    pub stable_below: Option<f64>,
}

/// `|z|` above `1 + this` is growth: the free motions' eigenvalues `z = 1` (a free base's
/// translation, a wheel, a hinge without a spring: Jordan blocks, which round-off splits by
/// about `√ε`; 1.3e-7 on the test's bus) and the undamped modes' `|z| = 1` are not. A loop
/// growing by less than this a sample takes over 70 000 samples to double.
const GROWTH_TOLERANCE: f64 = 1e-5;

/// A sampled attitude law (`[effects.attitude_control]` with a `period`) on the scene's linear
/// motions at the initial state (as [`rk4_limit`](super::step_limit::rk4_limit)'s: `M` of the tree with the rotors, `K` and
/// `D` of `hinges`' continuous gains, friction and modes): the bus torque
/// `u = −kp θ − kd ω` taken at each sample and held to the next (zero-order hold), through
/// the rotors' commands `τ = −A⁺ u`. Over one period the plant `ẋ = A x + B u` gives
/// `x⁺ = Φ x + Γ u` (`[[Φ, Γ], [0, 1]] = exp([[A, B], [0, 0]] T)`), so the loop is
/// `x⁺ = (Φ − Γ G) x` with `u = −G x`; it is stable where every eigenvalue has `|z| <= 1`.
/// A property of the design (the flight software would do the same), not of the
/// integrator. `None` where `M` is not positive definite, the base is not free or the tree
/// has not the law's rotors.
pub fn sampled_attitude(
    flex: &FlexModel,
    q: &[f64],
    hinges: &HingeGains,
    law: &AttitudeGains,
    period: f64,
) -> Option<SampledLoop> {
    let dofs = law.rotor_dofs(flex, hinges)?;
    let n = flex.nv();
    let (km, dm) = diagonal_matrices(flex, hinges);
    let (a, m_inv) = plant(flex, q, &km, &dm)?;
    // B = [0; M⁻¹ Q_u]: the rotors' generalised forces −A⁺ u.
    let mut qu = DMatrix::zeros(n, 3);
    for (r, &dof) in dofs.iter().enumerate() {
        for c in 0..3 {
            qu[(dof, c)] = -law.allocation[(r, c)];
        }
    }
    let mut bm = DMatrix::zeros(2 * n, 3);
    bm.view_mut((n, 0), (n, 3)).copy_from(&(&m_inv * qu));
    let mut g = DMatrix::zeros(3, 2 * n);
    for c in 0..3 {
        g[(c, c)] = law.kp;
        g[(c, n + c)] = law.kd;
    }
    let growth = |t: f64| -> Option<f64> {
        let mut aug = DMatrix::zeros(2 * n + 3, 2 * n + 3);
        aug.view_mut((0, 0), (2 * n, 2 * n)).copy_from(&(&a * t));
        aug.view_mut((0, 2 * n), (2 * n, 3)).copy_from(&(&bm * t));
        let e = aug.exp();
        let phi = e.view((0, 0), (2 * n, 2 * n)).into_owned();
        let gamma = e.view((0, 2 * n), (2 * n, 3)).into_owned();
        // z = 1 + t μ, μ the eigenvalues of (Φ − Γ G − 1)/t: a short period puts every z
        // near 1, where the Schur iteration on Φ − Γ G itself does not converge, while
        // (Φ − Γ G − 1)/t tends to the continuous loop's matrix.
        let mut closed = phi - gamma * &g;
        for i in 0..2 * n {
            closed[(i, i)] -= 1.0;
        }
        let mu = Schur::try_new(closed / t, f64::EPSILON, 10_000)?.complex_eigenvalues();
        let one = Complex::new(1.0, 0.0);
        let largest = mu.iter().map(|m| (one + m * t).norm()).fold(0.0, f64::max);
        largest.is_finite().then_some(largest)
    };
    let at = growth(period)?;
    // A period whose loop the decomposition cannot resolve is taken for stable: the warning
    // names only the growth it measured.
    let stable = |t: f64| growth(t).is_none_or(|z| z <= 1.0 + GROWTH_TOLERANCE);
    // The first unstable period of a scan from zero, then bisection below it.
    let stable_below = (at > 1.0 + GROWTH_TOLERANCE).then(|| last_stable(stable, period, 40, 40));
    Some(SampledLoop {
        growth: at,
        stable_below,
    })
}
