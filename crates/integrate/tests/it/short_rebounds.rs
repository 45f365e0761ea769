//! A rebound shorter than a step: an event handled at the start of a step restarts from
//! g = 0; when its function leaves zero and comes back before the step ends, the end points
//! have the same sign and only the dense output shows the second crossing. Without probing
//! it, a ball bouncing with little restitution under fixed steps fell through the floor (the
//! two_wings scene's boom elbow crept through its rebound stop the same way).

use crate::common;

use common::{Ball, collect};
use satsim_integrate::{EventAction, Method, Options, Output, StopReason};

#[test]
fn rebounds_shorter_than_a_step_are_found_under_every_method() {
    // Rebound speeds 0.22, 0.011 m/s: flights of 45 ms and 2.3 ms, against steps of 50 ms.
    let (h, e, v_rest) = (1.0, 0.05, 5e-3);
    let resting = || Ball {
        v_rest,
        ..Ball::new(h, e, EventAction::Reset)
    };
    let expected = resting().expected(usize::MAX);
    assert_eq!(expected.len(), 3);
    // The second flight is shorter than a step, the third much shorter.
    assert!(expected[1] - expected[0] < 0.05 && expected[2] - expected[1] < 0.005);
    for method in Method::ALL {
        let mut opts = Options::new(method).with_tolerances(1e-10, 1e-12);
        if method == Method::Rk4 {
            opts = opts.with_fixed_step(0.05);
        } else {
            // Adaptive methods take long steps on this quadratic: force them to be long.
            opts.h_max = 0.05;
        }
        let mut ball = resting();
        let (r, rows) = collect(&mut ball, &opts, &[h, 0.0], 2.0, &Output::Steps);
        let stats = r.unwrap();
        assert!(
            matches!(stats.stop, StopReason::Event { k: 0 }),
            "{method}: the ball must come to rest, not fall: {:?}",
            stats.stop
        );
        assert_eq!(
            ball.impacts.len(),
            expected.len(),
            "{method}: {:?}",
            ball.impacts
        );
        for (t, te) in ball.impacts.iter().zip(&expected) {
            assert!(
                (t - te).abs() < 1e-8,
                "{method}: impact at {t}, expected {te}"
            );
        }
        for (t, x) in &rows {
            assert!(x[0] > -1e-9, "{method}: ball at {} at t = {t}", x[0]);
        }
    }
}
