//! `satsim run` in bounded memory: rows stream to the CSV and into a bounded decimation for
//! the plots, so the peak memory of a run does not grow with its number of rows. (The 10⁶-row
//! figure is measured with `/usr/bin/time -v`, see docs/src/results/hard-cases.md; this test
//! runs 3·10⁵ rows, which kept in memory as before took well over 64 MiB.)

#![cfg(unix)]

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};

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

/// Runs `satsim args` in `dir` and reaps it with `wait4`: whether it succeeded, its standard
/// output and error, and its own peak resident memory (KiB). Its own: the other tests of this
/// binary run their children (campaigns, the browser) in parallel from the same process, so
/// `RUSAGE_CHILDREN` would report the largest of theirs.
fn run_measured(dir: &Path, args: &[&str]) -> (bool, String, String, i64) {
    #[allow(clippy::zombie_processes)] // reaped below by `wait4`, which returns its rusage
    let mut child = Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err_pipe = child.stderr.take().unwrap();
    let err = std::thread::spawn(move || {
        let mut e = String::new();
        err_pipe.read_to_string(&mut e).unwrap();
        e
    });
    let mut out = String::new();
    child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut out)
        .unwrap();
    let err = err.join().unwrap();
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `status` and `u` are valid to fill; the child is ours and not yet reaped (`child`
    // is dropped without waiting).
    let reaped = unsafe { libc::wait4(pid, &mut status, 0, &mut u) };
    assert_eq!(reaped, pid, "wait4");
    let ok = libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0;
    (ok, out, err, u.ru_maxrss)
}

#[test]
fn a_long_run_stays_under_64_mib_and_its_plots_under_1_mib() {
    let dir = satsim_testkit::temp_dir("memory");
    std::fs::write(dir.join("bus.toml"), MODEL).unwrap();
    std::fs::write(dir.join("long.toml"), SCENE).unwrap();
    let (ok, out, err, rss) = run_measured(&dir, &["run", "long.toml"]);
    assert!(ok, "{err}");
    assert!(out.contains("(300001 rows)"), "{out}");
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
