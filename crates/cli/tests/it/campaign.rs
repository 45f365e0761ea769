//! `satsim campaign` (contract section 8): reproducibility across threads and shards, rows
//! equal to `satsim run` of the substituted scene, failed runs, resume, scheduler
//! environments, bad input.

use crate::common;
use common::root;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const SCHEDULER_VARS: [&str; 6] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_MIN",
    "JOB_COMPLETION_INDEX",
    "AWS_BATCH_JOB_ARRAY_INDEX",
    "AWS_BATCH_JOB_ARRAY_SIZE",
];

fn satsim_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_satsim"));
    c.args(args).current_dir(dir);
    for v in SCHEDULER_VARS {
        c.env_remove(v);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("run satsim")
}

fn satsim(dir: &Path, args: &[&str]) -> Output {
    satsim_env(dir, args, &[])
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "status {:?}\nstdout: {}\nstderr: {}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn temp_dir(test: &str) -> PathBuf {
    satsim_testkit::temp_dir_with(&format!("campaign-{test}"), &["examples/satellite.toml"])
}

/// The scene of most tests, with `{placeholders}` for the dispersed numbers; `nominal`
/// fills them with the values as written.
const TEMPLATE: &str = r#"model = "{model}"
duration = 3.0

[initial]
base = { attitude = [1.0, 0.0, 0.0, 0.0], angular_velocity = [0.001, -0.002, 0.0015] }
hinges = { angle = [0.3, -0.2, 0.1, {a3}, -1.0], rate = [0.01, 0.02, -0.01, 0.05, -0.04] }

[integrator]
method = "rk4"
step = 0.01

[output]
every = 0.25
plots = false

[effects.hinge_springs]
stiffness = [{k0}, {k1}, {k2}, {k3}, {k4}]
damping = [1.0, 1.0, 1.0, 0.5, 0.5]
"#;

const CAMPAIGN: &str = r#"
[campaign]
runs = 12
seed = 42

[[campaign.disperse]]
key = "effects.hinge_springs.stiffness"
scale = { sigma = 0.1 }

[[campaign.disperse]]
key = "initial.hinges.angle"
index = 3
normal = { sigma = 0.05 }

[[campaign.disperse]]
key = "model.body.3.mass"
uniform = { low = -2.0, high = 2.0 }
"#;

const NOMINAL: [(&str, &str); 6] = [
    ("{a3}", "1.2"),
    ("{k0}", "50.0"),
    ("{k1}", "50.0"),
    ("{k2}", "50.0"),
    ("{k3}", "2.0"),
    ("{k4}", "2.0"),
];

fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut s = template.to_owned();
    for (k, v) in values {
        s = s.replace(k, v);
    }
    s
}

fn write_campaign(dir: &Path, extra: &str) -> PathBuf {
    let text = fill(TEMPLATE, &NOMINAL).replace("{model}", "satellite.toml") + extra;
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Splits a CSV line (quoted fields allowed).
fn fields(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                out.last_mut().unwrap().push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') => quoted = true,
            (false, ',') => out.push(String::new()),
            (_, c) => out.last_mut().unwrap().push(c),
        }
    }
    out
}

#[test]
fn threads_and_shards_do_not_change_a_byte_of_runs_csv() {
    let dir = temp_dir("threads");
    write_campaign(&dir, CAMPAIGN);
    let whole = satsim(
        &dir,
        &["campaign", "scene.toml", "--out", "t1", "--threads", "1"],
    );
    // The whole campaign names its shard once, in the summary; a split one (below) also
    // before it runs, on standard error.
    let said = format!("{}{}", ok(&whole), String::from_utf8_lossy(&whole.stderr));
    assert_eq!(said.matches("0/1").count(), 1, "{said}");
    ok(&satsim(
        &dir,
        &["campaign", "scene.toml", "--out", "t2", "--threads", "2"],
    ));
    for i in 0..3 {
        let shard = format!("{i}/3");
        let out = format!("s{i}");
        let o = satsim(
            &dir,
            &[
                "campaign",
                "scene.toml",
                "--out",
                &out,
                "--shard",
                &shard,
                "--threads",
                "2",
            ],
        );
        ok(&o);
        assert!(String::from_utf8_lossy(&o.stderr).contains("--shard"));
        // A shard holds exactly its runs.
        let text = read(&dir.join(&out).join("runs.csv"));
        let ks: Vec<u64> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(ks, (0..12).filter(|k| k % 3 == i).collect::<Vec<u64>>());
    }
    // `satsim run` of a campaign scene runs the nominal scene.
    ok(&satsim(&dir, &["run", "scene.toml", "--out", "nominal"]));
    // Shards merged in any order.
    ok(&satsim(
        &dir,
        &["campaign", "merge", "s2", "s0", "s1", "--out", "merged"],
    ));

    let one = read(&dir.join("t1/runs.csv"));
    assert_eq!(one, read(&dir.join("t2/runs.csv")));
    assert_eq!(one, read(&dir.join("merged/runs.csv")));
    assert_eq!(
        read(&dir.join("t1/summary.json")),
        read(&dir.join("merged/summary.json"))
    );

    // Columns: run, the dispersed values, status, message, then final/min/max of every
    // trajectory column but t, in the trajectory's order.
    let header = fields(one.lines().next().unwrap());
    let expected_start = [
        "run",
        "effects.hinge_springs.stiffness[0]",
        "effects.hinge_springs.stiffness[1]",
        "effects.hinge_springs.stiffness[2]",
        "effects.hinge_springs.stiffness[3]",
        "effects.hinge_springs.stiffness[4]",
        "initial.hinges.angle[3]",
        "model.body.3.mass",
        "status",
        "message",
        "final_q_w",
        "min_q_w",
        "max_q_w",
        "final_q_x",
    ];
    assert_eq!(header[..expected_start.len()], expected_start);
    for c in ["angle_h4", "rate_h5", "kinetic_energy", "h_x", "h_y", "h_z"] {
        for s in ["final_", "min_", "max_"] {
            assert!(header.contains(&format!("{s}{c}")), "{s}{c}");
        }
    }
    let rows: Vec<Vec<String>> = one.lines().skip(1).map(fields).collect();
    assert_eq!(rows.len(), 12);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r[0], k.to_string());
        assert_eq!(r.len(), header.len());
        assert_eq!(r[8], "ok", "run {k}: {}", r[9]);
    }
    // The draws differ between runs and stay near their nominal values.
    let mass: Vec<f64> = rows.iter().map(|r| r[7].parse().unwrap()).collect();
    assert!(mass.iter().all(|m| (18.0..22.0).contains(m)));
    assert!(mass.windows(2).all(|w| w[0] != w[1]));

    // summary.json: counts and the statistics of every stat column.
    let s: serde_json::Value = serde_json::from_str(&read(&dir.join("t1/summary.json"))).unwrap();
    assert_eq!(s["runs"], 12);
    assert_eq!(s["ok"], 12);
    assert_eq!(s["failed"], 0);
    let col = |name: &str| -> Vec<f64> {
        let c = header.iter().position(|h| h == name).unwrap();
        rows.iter().map(|r| r[c].parse().unwrap()).collect()
    };
    for name in &header[10..] {
        let st = &s[name.as_str()];
        for p in ["p1", "p5", "p50", "p95", "p99", "mean", "std"] {
            assert!(st[p].is_f64(), "{name}.{p}");
        }
        let v = col(name);
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        assert!((st["mean"].as_f64().unwrap() - mean).abs() <= 1e-12 * mean.abs().max(1e-300));
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let p = |k: &str| st[k].as_f64().unwrap();
        assert!(lo <= p("p1") && p("p1") <= p("p5") && p("p5") <= p("p50"));
        assert!(p("p50") <= p("p95") && p("p95") <= p("p99") && p("p99") <= hi);
    }
    // Plots: envelopes of hinge angles and bus rates, histograms of chosen finals.
    for f in [
        "envelope_angle_h4.svg",
        "envelope_omega_z.svg",
        "histogram_final_angle_h4.svg",
    ] {
        assert!(read(&dir.join("t1").join(f)).starts_with("<svg"), "{f}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Final, minimum and maximum of every column but `t` of a trajectory CSV.
fn trajectory_stats(path: &Path) -> (Vec<String>, Vec<[f64; 3]>) {
    let text = read(path);
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let mut stats = vec![[f64::NAN, f64::INFINITY, f64::NEG_INFINITY]; header.len() - 1];
    for l in lines {
        for (c, v) in l.split(',').skip(1).enumerate() {
            let v: f64 = v.parse().unwrap();
            stats[c] = [v, stats[c][1].min(v), stats[c][2].max(v)];
        }
    }
    (header[1..].to_vec(), stats)
}

#[test]
fn a_row_equals_satsim_run_of_the_scene_with_its_drawn_values() {
    let dir = temp_dir("equals-run");
    write_campaign(&dir, CAMPAIGN);
    ok(&satsim(
        &dir,
        &["campaign", "scene.toml", "--out", "c", "--threads", "2"],
    ));
    let text = read(&dir.join("c/runs.csv"));
    let header = fields(text.lines().next().unwrap());
    let model = read(&dir.join("satellite.toml"));
    let panel = model.find("name = \"panel1\"").unwrap();
    let mass_at = panel + model[panel..].find("mass = 20.0").unwrap();
    for line in text.lines().skip(1).take(3) {
        let r = fields(line);
        let k = &r[0];
        // The scene with this run's values written in by hand (not by the campaign code).
        let m = format!(
            "{}mass = {}{}",
            &model[..mass_at],
            r[7],
            &model[mass_at + "mass = 20.0".len()..]
        );
        std::fs::write(dir.join(format!("model{k}.toml")), m).unwrap();
        let values = [
            ("{k0}", r[1].as_str()),
            ("{k1}", &r[2]),
            ("{k2}", &r[3]),
            ("{k3}", &r[4]),
            ("{k4}", &r[5]),
            ("{a3}", &r[6]),
        ];
        let scene = fill(TEMPLATE, &values).replace("{model}", &format!("model{k}.toml"));
        let scene_path = format!("run{k}.toml");
        std::fs::write(dir.join(&scene_path), scene).unwrap();
        let out = format!("run{k}");
        ok(&satsim(&dir, &["run", &scene_path, "--out", &out]));
        let (cols, stats) = trajectory_stats(&dir.join(&out).join("trajectory.csv"));
        for (c, name) in cols.iter().enumerate() {
            for (s, prefix) in ["final_", "min_", "max_"].iter().enumerate() {
                let h = format!("{prefix}{name}");
                let i = header.iter().position(|x| *x == h).unwrap();
                let campaign: f64 = r[i].parse().unwrap();
                assert_eq!(
                    campaign.to_bits(),
                    stats[c][s].to_bits(),
                    "run {k} {h}: campaign {campaign}, satsim run {}",
                    stats[c][s]
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn failed_runs_are_rows_with_their_message() {
    let dir = temp_dir("failed");
    // Masses drawn negative make invalid scenes; long durations exceed max_steps.
    let extra = r#"
[campaign]
runs = 16
seed = 3

[[campaign.disperse]]
key = "model.body.3.mass"
normal = { sigma = 25.0 }

[[campaign.disperse]]
key = "duration"
uniform = { low = -2.0, high = 2.0 }
"#;
    let scene = write_campaign(&dir, extra);
    let text = read(&scene).replace("step = 0.01", "step = 0.01\nmax_steps = 300");
    std::fs::write(&scene, text).unwrap();
    let out = satsim(&dir, &["campaign", "scene.toml", "--out", "c"]);
    let stdout = ok(&out);
    let text = read(&dir.join("c/runs.csv"));
    let header = fields(text.lines().next().unwrap());
    let rows: Vec<Vec<String>> = text.lines().skip(1).map(fields).collect();
    assert_eq!(rows.len(), 16);
    let (mut bad_mass, mut too_long, mut fine) = (0, 0, 0);
    for r in &rows {
        let mass: f64 = r[1].parse().unwrap();
        let duration: f64 = r[2].parse().unwrap();
        if mass < 0.0 {
            assert_eq!(r[3], "failed");
            assert!(r[4].contains("mass"), "{}", r[4]);
            bad_mass += 1;
        } else if duration > 3.0 + 1e-9 {
            assert_eq!(r[3], "failed", "duration {duration}");
            assert!(r[4].contains("step"), "{}", r[4]);
            too_long += 1;
        } else {
            assert_eq!(r[3], "ok", "{}", r[4]);
            fine += 1;
            continue;
        }
        // A failed run keeps its drawn values and leaves the statistics empty.
        assert!(r[5..].iter().all(String::is_empty));
        assert_eq!(r.len(), header.len());
    }
    assert!(
        bad_mass > 0 && too_long > 0 && fine > 0,
        "{bad_mass} {too_long} {fine}"
    );
    let s: serde_json::Value = serde_json::from_str(&read(&dir.join("c/summary.json"))).unwrap();
    assert_eq!(s["runs"], 16);
    assert_eq!(s["failed"], bad_mass + too_long);
    assert_eq!(s["ok"], fine);
    assert!(stdout.contains(&format!("{} failed", bad_mass + too_long)));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn resume_skips_the_runs_already_in_runs_csv() {
    let dir = temp_dir("resume");
    write_campaign(&dir, &CAMPAIGN.replace("runs = 12", "runs = 6"));
    ok(&satsim(&dir, &["campaign", "scene.toml", "--out", "full"]));
    let full = read(&dir.join("full/runs.csv"));
    // A campaign killed part-way: two finished runs in completion order, then half a row.
    let lines: Vec<&str> = full.lines().collect();
    std::fs::create_dir_all(dir.join("part")).unwrap();
    std::fs::copy(
        dir.join("full/campaign.json"),
        dir.join("part/campaign.json"),
    )
    .unwrap();
    let cut = &lines[2][..lines[2].len() / 2];
    std::fs::write(
        dir.join("part/runs.csv"),
        format!("{}\n{}\n{}\n{cut}", lines[0], lines[4], lines[2]),
    )
    .unwrap();
    let out = ok(&satsim(
        &dir,
        &["campaign", "scene.toml", "--out", "part", "--resume"],
    ));
    assert!(out.contains("ran        4 runs"), "{out}");
    assert!(out.contains("2 already in runs.csv"), "{out}");
    assert_eq!(read(&dir.join("part/runs.csv")), full);
    // Resuming a finished campaign runs nothing and changes nothing.
    let out = ok(&satsim(
        &dir,
        &["campaign", "scene.toml", "--out", "part", "--resume"],
    ));
    assert!(out.contains("ran        0 runs"), "{out}");
    assert_eq!(read(&dir.join("part/runs.csv")), full);
    // A folder of an earlier satsim, without the last column, is refused by name.
    std::fs::create_dir_all(dir.join("old")).unwrap();
    std::fs::copy(
        dir.join("full/campaign.json"),
        dir.join("old/campaign.json"),
    )
    .unwrap();
    let older: String = full
        .lines()
        .map(|l| format!("{}\n", l.rsplit_once(',').unwrap().0))
        .collect();
    assert!(full.lines().next().unwrap().ends_with(",stability_held"));
    std::fs::write(dir.join("old/runs.csv"), &older).unwrap();
    let o = satsim(
        &dir,
        &["campaign", "scene.toml", "--out", "old", "--resume"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("it lacks `stability_held`") && err.contains("earlier version"),
        "{err}"
    );
    assert_eq!(read(&dir.join("old/runs.csv")), older);
    // Another seed does not resume this folder.
    let scene = read(&dir.join("scene.toml")).replace("seed = 42", "seed = 43");
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let o = satsim(
        &dir,
        &["campaign", "scene.toml", "--out", "part", "--resume"],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("other drawn values"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn resume_and_merge_refuse_runs_of_another_scene() {
    let dir = temp_dir("resume_scene");
    write_campaign(&dir, &CAMPAIGN.replace("runs = 12", "runs = 2"));
    let run = |args: &[&str]| satsim(&dir, args);
    ok(&run(&["campaign", "scene.toml", "--out", "a"]));
    let json = read(&dir.join("a/campaign.json"));
    assert!(json.contains("\"scene_digest\""), "{json}");
    // The same scene resumes (nothing left to run).
    ok(&run(&["campaign", "scene.toml", "--out", "a", "--resume"]));
    // Another --set value, or a changed model file, draws the same values but is another
    // scene: refused, naming campaign.json, and nothing in the folder changes.
    let runs = read(&dir.join("a/runs.csv"));
    let refused = |o: &Output| {
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("campaign.json") && err.contains("another scene"),
            "{err}"
        );
    };
    refused(&run(&[
        "campaign",
        "scene.toml",
        "--out",
        "a",
        "--resume",
        "--set",
        "duration=2.0",
    ]));
    let model = read(&dir.join("satellite.toml"));
    let heavier = model.replacen("mass = 800.0", "mass = 801.0", 1);
    assert_ne!(heavier, model, "the model file has a bus of 800 kg");
    std::fs::write(dir.join("satellite.toml"), &heavier).unwrap();
    refused(&run(&["campaign", "scene.toml", "--out", "a", "--resume"]));
    assert_eq!(read(&dir.join("a/runs.csv")), runs);
    assert_eq!(read(&dir.join("a/campaign.json")), json);
    // Shards of the two scenes do not merge.
    ok(&run(&["campaign", "scene.toml", "--out", "b"]));
    let o = run(&["campaign", "merge", "a", "b", "--out", "m"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("another scene"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ctrl_c_keeps_the_finished_runs_and_resume_completes_them() {
    let dir = temp_dir("sigint");
    let p = write_campaign(&dir, &CAMPAIGN.replace("runs = 12", "runs = 400"));
    // Runs long enough to be interrupted part-way (400 of them would take minutes).
    std::fs::write(&p, read(&p).replace("duration = 3.0", "duration = 60.0")).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(["campaign", "scene.toml", "--out", "part", "--threads", "1"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let runs_csv = dir.join("part/runs.csv");
    let start = Instant::now();
    while std::fs::read_to_string(&runs_csv).map_or(0, |t| t.lines().count()) < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no runs written"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(o.stdout.is_empty());
    // Every finished run is in runs.csv as a complete row; nothing was summarised.
    let text = read(&runs_csv);
    assert!(text.ends_with('\n'));
    let held = text.lines().count() - 1;
    assert!((2..400).contains(&held), "{held} runs held");
    let expected = format!(
        "interrupted: {held} runs in {}, {} not run; continue with --resume",
        Path::new("part").join("runs.csv").display(),
        400 - held
    );
    assert!(err.lines().any(|l| l == expected), "{err}");
    assert!(!dir.join("part/summary.json").exists());
    // Resumed as a campaign a little longer than what it holds, it completes, equal to the
    // same campaign run without interruption.
    let last = text
        .lines()
        .skip(1)
        .map(|l| fields(l)[0].parse::<u64>().unwrap())
        .max()
        .unwrap();
    let runs = format!("campaign.runs={}", last + 3);
    let args = |out: &'static str, resume: bool| {
        let mut a = vec!["campaign", "scene.toml", "--out", out, "--set", &runs];
        if resume {
            a.push("--resume");
        }
        a
    };
    ok(&satsim(&dir, &args("part", true)));
    ok(&satsim(&dir, &args("fresh", false)));
    assert_eq!(read(&runs_csv), read(&dir.join("fresh/runs.csv")));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_shard_comes_from_the_scheduler_environment() {
    let dir = temp_dir("env");
    write_campaign(&dir, &CAMPAIGN.replace("runs = 12", "runs = 5"));
    let ks = |out: &str| -> Vec<u64> {
        read(&dir.join(out).join("runs.csv"))
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap().parse().unwrap())
            .collect()
    };
    for (env, args, expect, says) in [
        (
            vec![
                ("SLURM_ARRAY_TASK_ID", "1"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            vec![],
            vec![1, 3],
            "SLURM_ARRAY_TASK_ID=1",
        ),
        (
            vec![("JOB_COMPLETION_INDEX", "2")],
            vec!["--shards", "3"],
            vec![2],
            "JOB_COMPLETION_INDEX=2",
        ),
        (
            vec![
                ("AWS_BATCH_JOB_ARRAY_INDEX", "0"),
                ("AWS_BATCH_JOB_ARRAY_SIZE", "2"),
            ],
            vec![],
            vec![0, 2, 4],
            "AWS_BATCH_JOB_ARRAY_INDEX=0",
        ),
    ] {
        let mut a = vec!["campaign", "scene.toml", "--out", "e"];
        a.extend(args);
        let o = satsim_env(&dir, &a, &env);
        ok(&o);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains(says), "{stderr}");
        assert_eq!(ks("e"), expect);
    }
    // An indexed Job without the shard count is bad input.
    let o = satsim_env(
        &dir,
        &["campaign", "scene.toml", "--out", "e"],
        &[("JOB_COMPLETION_INDEX", "0")],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shards"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_campaign_input_exits_2_naming_the_key() {
    let dir = temp_dir("bad");
    let disperse =
        |body: &str| format!("\n[campaign]\nruns = 3\n\n[[campaign.disperse]]\n{body}\n");
    for (extra, needles) in [
        (
            "\n[campaign]\nruns = 3\nrnus = 4\n".to_owned(),
            vec!["rnus", "scene.toml:22:"],
        ),
        ("\n[campaign]\nruns = 0\n".to_owned(), vec!["campaign.runs"]),
        ("\nduration = 1.0\n".to_owned(), vec!["[campaign]"]),
        (
            disperse("key = \"initial.hinges.angle\"\nindex = 5\nnormal = { sigma = 0.1 }"),
            vec![
                "initial.hinges.angle",
                "index 5 is out of range",
                "scene.toml:2",
            ],
        ),
        (
            disperse("key = \"effects.hinge_springs.damping\"\nnormal = { sigma = -0.1 }"),
            vec!["effects.hinge_springs.damping", "sigma"],
        ),
        (
            disperse("key = \"duration\"\nuniform = { low = 1.0, high = -1.0 }"),
            vec!["duration", "above"],
        ),
        (
            disperse("key = \"effects.hinge_springs.stifness\"\nscale = { sigma = 0.1 }"),
            vec!["effects.hinge_springs.stifness", "stifness"],
        ),
        (
            disperse("key = \"integrator.method\"\nnormal = { sigma = 0.1 }"),
            vec!["integrator.method", "not a number"],
        ),
        (
            disperse("key = \"model.body.6.mass\"\nnormal = { sigma = 0.1 }"),
            vec!["model.body.6.mass", "out of range"],
        ),
        (
            disperse("key = \"duration\"\nnormal = { sigma = 0.1 }\nscale = { sigma = 0.1 }"),
            vec!["duration", "exactly one law"],
        ),
        (
            disperse("key = \"duration\"\nnormal = { sigma = 0.1, mean = 2.0 }"),
            vec!["mean"],
        ),
    ] {
        let scene = write_campaign(&dir, "");
        let text = read(&scene).replace("duration = 3.0\n", "");
        let text = if extra.contains("duration = 1.0") {
            format!("duration = 3.0\n{text}")
        } else {
            format!("duration = 3.0\n{text}{extra}")
        };
        std::fs::write(&scene, text).unwrap();
        let o = satsim(&dir, &["campaign", "scene.toml", "--out", "c"]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra}: {stderr}");
        assert!(stderr.contains("scene.toml"), "{stderr}");
        for n in needles {
            assert!(stderr.contains(n), "{extra}: `{n}` not in {stderr}");
        }
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
    for (args, needle) in [
        (
            vec!["campaign", "scene.toml", "--shard", "3/3"],
            "out of range",
        ),
        (
            vec!["campaign", "scene.toml", "--threads", "0"],
            "--threads",
        ),
        (vec!["campaign", "merge", "--out", "m"], "<SHARD_DIR>..."),
        (
            vec!["campaign", "merge", "nowhere", "--out", "m"],
            "nowhere",
        ),
    ] {
        let o = satsim(&dir, &args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Dispersions that every run would ignore or refuse, refused when the campaign starts (not
/// a campaign of failed runs that exits 0): the sensors' seed, a whole-number key, a law that
/// draws infinities, a number of runs past the bound; and a merge of one folder twice.
#[test]
fn dispersions_the_runs_cannot_take_are_refused_up_front() {
    let dir = temp_dir("refused");
    let gyro = "\n[sensors]\nseed = 5\n[[sensors.gyro]]\nname = \"g\"\nbody = \"bus\"\nperiod = 0.5\nnoise_density = 1e-4\n";
    let disperse =
        |body: &str| format!("{gyro}\n[campaign]\nruns = 3\n\n[[campaign.disperse]]\n{body}\n");
    for (extra, needles) in [
        (
            disperse("key = \"sensors.seed\"\nnormal = { sigma = 2.0 }"),
            vec![
                "sensors.seed",
                "cannot be dispersed",
                "each run writes its own",
            ],
        ),
        (
            disperse("key = \"integrator.max_steps\"\nnormal = { sigma = 10.0 }"),
            vec!["integrator.max_steps", "whole numbers"],
        ),
        (
            disperse("key = \"model.body.3.mass\"\nnormal = { sigma = 1e308 }"),
            vec!["model.body.3.mass", "normal.sigma", "infinity"],
        ),
        (
            disperse("key = \"model.body.3.mass\"\nscale = { sigma = 1e307 }"),
            vec!["model.body.3.mass", "scale.sigma", "infinity"],
        ),
        (
            disperse("key = \"model.body.3.mass\"\nuniform = { low = -1e308, high = 1e308 }"),
            vec!["model.body.3.mass", "uniform.low", "infinity"],
        ),
        (
            format!("\n[campaign]\nruns = {}\n", i64::MAX),
            vec!["campaign.runs", "1000000000"],
        ),
    ] {
        let scene = write_campaign(&dir, "");
        let text =
            read(&scene).replace("step = 0.01\n", "step = 0.01\nmax_steps = 100000\n") + &extra;
        std::fs::write(&scene, text).unwrap();
        let o = satsim(&dir, &["campaign", "scene.toml", "--out", "c"]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra}: {stderr}");
        assert!(stderr.contains("scene.toml:"), "{stderr}");
        for n in needles {
            assert!(stderr.contains(n), "{extra}: `{n}` not in {stderr}");
        }
        assert!(!dir.join("c/runs.csv").exists(), "{extra}: no run is made");
    }
    // One folder merged with itself, or two copies of one shard, would count traces twice.
    let scene = write_campaign(&dir, CAMPAIGN);
    let scene = scene.to_str().unwrap();
    ok(&satsim(
        &dir,
        &["campaign", scene, "--shard", "0/2", "--out", "s0"],
    ));
    ok(&satsim(
        &dir,
        &["campaign", scene, "--shard", "1/2", "--out", "s1"],
    ));
    copy_dir(&dir.join("s0"), &dir.join("s0copy"));
    for (args, needle) in [
        (
            vec!["campaign", "merge", "s0", "s1", "s0", "--out", "m"],
            "given twice",
        ),
        (
            vec!["campaign", "merge", "s0", "./s0", "--out", "m"],
            "given twice",
        ),
        (
            vec!["campaign", "merge", "s0", "s1", "s0copy", "--out", "m"],
            "both hold shard 0/2",
        ),
    ] {
        let o = satsim(&dir, &args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
    ok(&satsim(
        &dir,
        &["campaign", "merge", "s0", "s1", "--out", "m"],
    ));
    let _ = std::fs::remove_dir_all(&dir);
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// `campaign SCENE --out OUT --set S...` and then `extra`.
fn campaign_args<'a>(
    scene: &'a str,
    out: &'a str,
    sets: &[&'a str],
    extra: &[&'a str],
) -> Vec<&'a str> {
    let mut args = vec!["campaign", scene, "--out", out];
    for set in sets {
        args.extend(["--set", set]);
    }
    args.extend_from_slice(extra);
    args
}

/// Several runs per core in SIMD lanes give every file of the campaign byte for byte as one
/// run at a time does: the deployment campaign (latches: lock masks that differ between the
/// runs of a batch, events located by one run alone, runs that end apart) and the peer
/// benchmark's campaign, on one and two threads, with a run count that leaves a batch's
/// places empty at the end.
#[test]
fn lanes_do_not_change_a_byte_of_the_campaign() {
    let dir = temp_dir("lanes");
    for (scene, set) in [
        ("examples/scenes/deploy_campaign.toml", "duration=20.0"),
        (
            "benches/campaign_vs_mujoco/deploy_vs_mujoco.toml",
            "duration=60.0",
        ),
    ] {
        let scene = root().join(scene);
        let scene = scene.to_str().unwrap();
        let run = |out: &str, extra: &[&str]| {
            let sets = ["campaign.runs=9", set];
            ok(&satsim_env(
                &dir,
                &campaign_args(scene, out, &sets, extra),
                &[],
            ))
        };
        let alone = run("alone", &["--no-lanes", "--threads", "1"]);
        assert!(!alone.contains("lanes "), "{alone}");
        for threads in ["1", "2"] {
            let lanes = run("lanes", &["--threads", threads]);
            // The lanes were used: most right-hand sides solved in them.
            let line = lanes
                .lines()
                .find(|l| l.starts_with("lanes "))
                .unwrap_or_else(|| panic!("no lanes line in {lanes}"));
            let share: f64 = line
                .split("; ")
                .nth(1)
                .unwrap()
                .split(' ')
                .next()
                .unwrap()
                .parse()
                .unwrap();
            assert!(share > 50.0, "{line}");
            for file in ["runs.csv", "traces.csv", "summary.json"] {
                assert_eq!(
                    read(&dir.join("alone").join(file)),
                    read(&dir.join("lanes").join(file)),
                    "{scene}: {file} on {threads} threads"
                );
            }
        }
    }
}

/// `SATSIM_INSTRUCTIONS` caps the instructions of every kernel (one run's and the lanes'),
/// and so the runs per batch: every cap gives every file of the campaign byte for byte as
/// the CPU's widest does, one run at a time and in lanes; the baseline's batches hold two
/// runs. A value that names no instruction set is refused before anything runs.
#[test]
fn every_instruction_cap_gives_the_same_bytes() {
    let dir = temp_dir("instructions");
    let scene = root().join("examples/scenes/deploy_campaign.toml");
    let scene = scene.to_str().unwrap();
    let sets = ["campaign.runs=5", "duration=20.0"];
    let run = |out: &str, extra: &[&str], env: &[(&str, &str)]| {
        ok(&satsim_env(
            &dir,
            &campaign_args(scene, out, &sets, extra),
            env,
        ))
    };
    run("widest", &["--no-lanes", "--threads", "1"], &[]);
    for cap in ["baseline", "avx2", "avx512"] {
        let env = [("SATSIM_INSTRUCTIONS", cap)];
        run("alone", &["--no-lanes", "--threads", "1"], &env);
        let lanes = run("lanes", &["--threads", "1"], &env);
        if cap == "baseline" {
            assert!(lanes.contains("lanes      2 runs per core"), "{lanes}");
        }
        for out in ["alone", "lanes"] {
            for file in ["runs.csv", "traces.csv", "summary.json"] {
                assert_eq!(
                    read(&dir.join("widest").join(file)),
                    read(&dir.join(out).join(file)),
                    "{cap}, {out}: {file}"
                );
            }
        }
    }
    let o = satsim_env(
        &dir,
        &["campaign", scene, "--out", "bad"],
        &[("SATSIM_INSTRUCTIONS", "sse9")],
    );
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("SATSIM_INSTRUCTIONS") && stderr.contains("`sse9`"),
        "{stderr}"
    );
    assert!(!dir.join("bad").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The stiff hinge (56.7 Hz) under DP5(4), as `satsim run` warns of its one run
/// (`run.rs`): every run's steps sit at the method's stability limit, each row says so in
/// `stability_held`, and the campaign warns once, counting them; under the scene's own
/// Radau IIA, no row and no warning.
#[test]
fn runs_held_by_a_stability_limit_are_counted_and_warned_of() {
    let dir = temp_dir("held");
    let shipped = read(&root().join("examples/scenes/stiff_hinge.toml"));
    let text = shipped
        .replace(
            "model = \"../satellite.toml\"",
            "model = \"satellite.toml\"",
        )
        .replace("duration = 100.0", "duration = 10.0")
        + r#"
[campaign]
runs = 3
seed = 7

[[campaign.disperse]]
key = "initial.base.angular_velocity"
index = 0
normal = { sigma = 0.005 }
"#;
    std::fs::write(dir.join("scene.toml"), text).unwrap();
    let campaign = |out: &str, extra: &[&str]| {
        let mut args = vec!["campaign", "scene.toml", "--out", out, "--threads", "1"];
        args.extend_from_slice(extra);
        let o = satsim(&dir, &args);
        ok(&o);
        let runs = read(&dir.join(out).join("runs.csv"));
        let mut lines = runs.lines();
        let header = fields(lines.next().unwrap());
        assert_eq!(header.last().map(String::as_str), Some("stability_held"));
        let held: Vec<String> = lines.map(|l| fields(l).pop().unwrap()).collect();
        (held, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (held, err) = campaign("dp54", &["--set", "integrator.method=dp54"]);
    assert_eq!(held, ["1", "1", "1"], "{err}");
    assert!(
        err.contains(
            "3 of the 3 finished runs took steps held by their explicit method's stability limit"
        ) && err.contains("`integrator.method = \"radau5\"` (implicit) steps over that motion"),
        "{err}"
    );
    let (held, err) = campaign("radau5", &[]);
    assert_eq!(held, ["0", "0", "0"], "{err}");
    assert!(!err.contains("stability limit"), "{err}");
}
