//! Shards: which runs of a campaign one job runs (`k % count == index`), from `--shard I/N`
//! or from a cluster scheduler's environment.

use std::fmt;
use std::str::FromStr;

/// One shard of a campaign: the runs `k` with `k % count == index`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, `0 <= index < count`.
    pub index: u64,
    /// The number of shards, >= 1.
    pub count: u64,
}

impl Shard {
    /// The whole campaign.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// A checked shard.
    pub fn new(index: u64, count: u64) -> Result<Shard, String> {
        if count == 0 {
            return Err("the number of shards must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "shard {index} is out of range: shards are numbered 0 to {}",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }

    /// Whether run `k` belongs to this shard.
    pub fn contains(&self, k: u64) -> bool {
        k % self.count == self.index
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;
    /// `I/N`, `0 <= I < N`.
    fn from_str(s: &str) -> Result<Shard, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("expected I/N (such as 0/4), got `{s}`"))?;
        let parse = |x: &str| {
            x.trim()
                .parse::<u64>()
                .map_err(|_| format!("expected I/N with whole numbers I and N, got `{s}`"))
        };
        Shard::new(parse(i)?, parse(n)?)
    }
}

/// Where a shard came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShardChoice {
    /// The shard.
    pub shard: Shard,
    /// Where it came from, for the log: `--shard`, `SLURM_ARRAY_TASK_ID=3 of
    /// SLURM_ARRAY_TASK_COUNT=8`, … or `no --shard and no scheduler environment`.
    pub source: String,
}

/// The shard to run: `--shard` (`flag`) if given; else a Slurm job array
/// (`SLURM_ARRAY_TASK_ID` with `SLURM_ARRAY_TASK_COUNT`, offset by `SLURM_ARRAY_TASK_MIN` when
/// the array does not start at 0); else a Kubernetes indexed Job (`JOB_COMPLETION_INDEX`, with
/// the count from `shards`, `--shards N`: the Job's `completions`, which Kubernetes does not
/// put in the pod's environment); else an AWS Batch array job (`AWS_BATCH_JOB_ARRAY_INDEX`
/// with `AWS_BATCH_JOB_ARRAY_SIZE`); else the whole campaign. `env` reads a variable.
pub fn choose_shard(
    flag: Option<Shard>,
    shards: Option<u64>,
    env: impl Fn(&str) -> Option<String>,
) -> Result<ShardChoice, String> {
    if let Some(shard) = flag {
        return Ok(ShardChoice {
            shard,
            source: "--shard".into(),
        });
    }
    let num = |name: &str| -> Result<Option<u64>, String> {
        match env(name) {
            None => Ok(None),
            Some(v) if v.trim().is_empty() => Ok(None),
            Some(v) => v
                .trim()
                .parse::<u64>()
                .map(Some)
                .map_err(|_| format!("{name}={v} is not a whole number")),
        }
    };
    if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
        let count = num("SLURM_ARRAY_TASK_COUNT")?.ok_or(
            "SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not: pass --shard I/N",
        )?;
        let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let index = id.checked_sub(min).ok_or_else(|| {
            format!("SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}")
        })?;
        let shard = Shard::new(index, count).map_err(|e| {
            format!("SLURM_ARRAY_TASK_ID={id}, SLURM_ARRAY_TASK_COUNT={count}: {e} (a Slurm array for a campaign must be contiguous, such as --array=0-{})", count.max(1) - 1)
        })?;
        let offset = if min > 0 {
            format!(" minus SLURM_ARRAY_TASK_MIN={min}")
        } else {
            String::new()
        };
        return Ok(ShardChoice {
            shard,
            source: format!(
                "SLURM_ARRAY_TASK_ID={id}{offset} of SLURM_ARRAY_TASK_COUNT={count} (Slurm job array)"
            ),
        });
    }
    if let Some(index) = num("JOB_COMPLETION_INDEX")? {
        let count = shards.ok_or(
            "JOB_COMPLETION_INDEX is set (a Kubernetes indexed Job) but the number of shards is not known: pass --shards N with the Job's completions",
        )?;
        let shard = Shard::new(index, count)
            .map_err(|e| format!("JOB_COMPLETION_INDEX={index}, --shards {count}: {e}"))?;
        return Ok(ShardChoice {
            shard,
            source: format!(
                "JOB_COMPLETION_INDEX={index} of --shards {count} (Kubernetes indexed Job)"
            ),
        });
    }
    if let Some(index) = num("AWS_BATCH_JOB_ARRAY_INDEX")? {
        let count = num("AWS_BATCH_JOB_ARRAY_SIZE")?.ok_or(
            "AWS_BATCH_JOB_ARRAY_INDEX is set but AWS_BATCH_JOB_ARRAY_SIZE is not: pass --shard I/N",
        )?;
        let shard = Shard::new(index, count).map_err(|e| {
            format!("AWS_BATCH_JOB_ARRAY_INDEX={index}, AWS_BATCH_JOB_ARRAY_SIZE={count}: {e}")
        })?;
        return Ok(ShardChoice {
            shard,
            source: format!(
                "AWS_BATCH_JOB_ARRAY_INDEX={index} of AWS_BATCH_JOB_ARRAY_SIZE={count} (AWS Batch array job)"
            ),
        });
    }
    if shards.is_some() {
        return Err(
            "--shards N is for a Kubernetes indexed Job, but JOB_COMPLETION_INDEX is not set"
                .into(),
        );
    }
    Ok(ShardChoice {
        shard: Shard::ALL,
        source: "no --shard and no scheduler environment: every run".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |n| {
            vars.iter()
                .find(|(k, _)| *k == n)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn parses_i_over_n() {
        assert_eq!("2/5".parse::<Shard>(), Ok(Shard { index: 2, count: 5 }));
        for bad in ["5/5", "1/0", "a/2", "3", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let s = Shard::new(1, 3).unwrap();
        assert_eq!(
            (0..9).filter(|k| s.contains(*k)).collect::<Vec<_>>(),
            [1, 4, 7]
        );
    }

    #[test]
    fn the_flag_wins_then_slurm_then_kubernetes_then_aws() {
        let all = [
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
            ("JOB_COMPLETION_INDEX", "1"),
            ("AWS_BATCH_JOB_ARRAY_INDEX", "2"),
            ("AWS_BATCH_JOB_ARRAY_SIZE", "4"),
        ];
        let flag = Shard::new(0, 2).unwrap();
        let c = choose_shard(Some(flag), None, env(&all)).unwrap();
        assert_eq!((c.shard, c.source.as_str()), (flag, "--shard"));
        let c = choose_shard(None, Some(6), env(&all)).unwrap();
        assert_eq!(c.shard, Shard::new(3, 8).unwrap());
        assert!(c.source.contains("Slurm"));
        let c = choose_shard(None, Some(6), env(&all[2..])).unwrap();
        assert_eq!(c.shard, Shard::new(1, 6).unwrap());
        assert!(c.source.contains("Kubernetes"));
        let c = choose_shard(None, None, env(&all[3..])).unwrap();
        assert_eq!(c.shard, Shard::new(2, 4).unwrap());
        assert!(c.source.contains("AWS"));
        let c = choose_shard(None, None, env(&[])).unwrap();
        assert_eq!(c.shard, Shard::ALL);
    }

    #[test]
    fn slurm_arrays_starting_above_zero_are_offset() {
        let v = [
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ];
        let c = choose_shard(None, None, env(&v)).unwrap();
        assert_eq!(c.shard, Shard::new(3, 4).unwrap());
    }

    #[test]
    fn incomplete_environments_are_errors() {
        for (vars, shards, why) in [
            (
                vec![("SLURM_ARRAY_TASK_ID", "1")],
                None,
                "SLURM_ARRAY_TASK_COUNT",
            ),
            (
                vec![
                    ("SLURM_ARRAY_TASK_ID", "9"),
                    ("SLURM_ARRAY_TASK_COUNT", "4"),
                ],
                None,
                "out of range",
            ),
            (vec![("JOB_COMPLETION_INDEX", "1")], None, "--shards"),
            (
                vec![("JOB_COMPLETION_INDEX", "x")],
                Some(2),
                "not a whole number",
            ),
            (vec![("AWS_BATCH_JOB_ARRAY_INDEX", "0")], None, "SIZE"),
            (vec![], Some(3), "JOB_COMPLETION_INDEX is not set"),
        ] {
            let e = choose_shard(None, shards, env(&vars)).unwrap_err();
            assert!(e.contains(why), "{e}");
        }
    }
}
