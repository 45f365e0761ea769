//! Campaign throughput (kept out of CI): runs per second of `examples/scenes/deploy_campaign.toml`
//! at 1, 2, 4, … threads up to every core, the parallel efficiency, and the per-run cost of
//! building a run's scene from its draw (substitute, parse, build) against the run itself.
//!
//! `cargo bench -p satsim-satellite --bench campaign` (`CAMPAIGN_BENCH_RUNS`, default 32:
//! runs per thread count).

use satsim_tools::campaign::{Campaign, Quiet, RunOptions, Shard, run_campaign};
use satsim_tools::scene::Scene;
use std::path::Path;
use std::time::Instant;

fn main() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/deploy_campaign.toml");
    let mut c = Campaign::read(&path).unwrap_or_else(|e| panic!("{e}"));
    c.runs = std::env::var("CAMPAIGN_BENCH_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(32);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());

    // Per-run set-up against the run.
    let n = 200;
    let started = Instant::now();
    for k in 0..n {
        let scene = Scene::parse(&c.scene_text(&c.draw(k)), &c.path).unwrap();
        std::hint::black_box(scene.simulation().unwrap());
    }
    let setup = started.elapsed().as_secs_f64() / n as f64;
    let started = Instant::now();
    for k in 0..4 {
        std::hint::black_box(c.run_one(k));
    }
    let run = started.elapsed().as_secs_f64() / 4.0;
    println!(
        "per run: set-up {:.3} ms (substitute, parse, build), whole run {:.1} ms: set-up is {:.2} %",
        1e3 * setup,
        1e3 * run,
        100.0 * setup / run
    );

    println!(
        "{} runs of {} s, {} cores available",
        c.runs, c.nominal.duration, cores
    );
    println!("threads  wall (s)  runs/s  speed-up  efficiency");
    let dir = std::env::temp_dir().join(format!("satsim-campaign-bench-{}", std::process::id()));
    let mut threads = vec![1];
    while threads.last().unwrap() * 2 <= cores {
        threads.push(threads.last().unwrap() * 2);
    }
    if *threads.last().unwrap() != cores {
        threads.push(cores);
    }
    let mut base = None;
    for t in threads {
        let opts = RunOptions {
            threads: Some(t),
            shard: Shard::ALL,
            resume: false,
            lanes: true,
        };
        let started = Instant::now();
        let report = run_campaign(&c, &dir, &opts, &Quiet).unwrap();
        let wall = started.elapsed().as_secs_f64();
        assert_eq!(report.finished.runs, c.runs);
        let rate = c.runs as f64 / wall;
        let b = *base.get_or_insert(rate);
        println!(
            "{t:7}  {wall:8.2}  {rate:6.2}  {:8.2}  {:9.0} %",
            rate / b,
            100.0 * rate / b / t as f64
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
