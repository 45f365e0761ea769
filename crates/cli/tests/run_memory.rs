//! `satsim run` in bounded memory: rows stream to the CSV and into a bounded decimation for
//! the plots, so the peak memory of a run does not grow with its number of rows. (The 10⁶-row
//! figure is measured with `/usr/bin/time -v`, see docs/src/results/hard-cases.md; this test
//! runs 3·10⁵ rows, which kept in memory as before took well over 64 MiB.)

#![cfg(unix)]

use std::process::Command;

const MODEL: &str = r#"[[body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]]
"#;

const SCENE: &str = r#"model = "bus.toml"
duration = 300.0
[initial]
base = { angular_velocity = [0.1, 0.2, 0.3] }
[integrator]
method = "rk4"
step = 0.001
[output]
every = 0.001
"#;

/// Peak resident memory (KiB) of the largest child waited for so far.
fn children_max_rss_kib() -> i64 {
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `u` is a valid rusage to fill.
    unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut u) };
    u.ru_maxrss
}

#[test]
fn a_long_run_stays_under_64_mib_and_its_plots_under_1_mib() {
    let dir = std::env::temp_dir().join(format!("satsim-memory-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bus.toml"), MODEL).unwrap();
    std::fs::write(dir.join("long.toml"), SCENE).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(["run", "long.toml"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("(300001 rows)"), "{out}");
    let rss = children_max_rss_kib();
    let plots = dir.join("out/long");
    let mut sizes = Vec::new();
    for f in ["attitude.svg", "rates.svg", "energy.svg", "momentum.svg"] {
        sizes.push((f, std::fs::metadata(plots.join(f)).unwrap().len()));
    }
    let _ = std::fs::remove_dir_all(&dir);
    println!("peak {} KiB; plots {sizes:?}", rss);
    assert!(rss < 64 * 1024, "peak memory {rss} KiB");
    for (f, size) in sizes {
        assert!(size < 1 << 20, "{f}: {size} bytes");
    }
}
