//! The instructions the kernels run on ([`Instructions`]): chosen once per process, the
//! widest the CPU has, capped by `SATSIM_INSTRUCTIONS`. [`crate::kernel::UnrolledAba`]
//! compiles one instance of its passes per choice for one run, and for lanes of runs the
//! baseline's and the one of their register size
//! ([`UnrolledAba::instance`](crate::kernel::UnrolledAba::instance)); every instance gives
//! the same bits.

use std::sync::OnceLock;

/// The instructions a kernel (one run or lanes) runs on, narrowest first: chosen at run
/// time, the widest the CPU has ([`Instructions::detected`], capped by
/// [`Instructions::ENV`]) unless
/// [`UnrolledAba::instructions`](crate::kernel::UnrolledAba::instructions) caps it further.
/// Every instance executes the same operations lane by lane (Rust does not contract
/// `a * b + c` into a fused multiply-add), so all give the same bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Instructions {
    /// The baseline target's (two `f64` per SSE2 instruction on x86-64; every other
    /// architecture).
    Baseline,
    /// x86-64 with AVX2: four `f64` per instruction, 16 vector registers.
    Avx2,
    /// x86-64 with AVX-512 (F and VL): eight `f64` per instruction, 32 vector registers.
    Avx512,
}

impl Instructions {
    /// The environment variable that caps the instructions every kernel runs on (and so the
    /// width of a campaign's batches): `baseline`, `avx2` or `avx512`. To measure what the
    /// wider instructions give on one machine, or to run the narrower code paths; the
    /// results are the same bits on all of them.
    pub const ENV: &'static str = "SATSIM_INSTRUCTIONS";

    /// The instructions the kernels run on: the widest of this CPU ([`Instructions::cpu`]),
    /// capped by [`Instructions::ENV`] where that is set to a valid value
    /// ([`Instructions::from_env`]; the command line refuses an invalid one, the library
    /// warns once on standard error and ignores it). Decided once per process; later calls
    /// are one load.
    pub fn detected() -> Self {
        static CHOSEN: OnceLock<Instructions> = OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let cpu = Self::cpu();
            match Self::from_env() {
                Ok(Some(cap)) => cap.min(cpu),
                Ok(None) => cpu,
                Err(e) => {
                    // Where no caller refused it first (the library, Python).
                    eprintln!("warning: {e}; ignored, the kernels use {cpu}");
                    cpu
                }
            }
        })
    }

    /// The widest instructions of this CPU (the standard library caches the detection).
    pub fn cpu() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl")
                && std::arch::is_x86_feature_detected!("avx2")
            {
                return Self::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                return Self::Avx2;
            }
        }
        Self::Baseline
    }

    /// The cap set by [`Instructions::ENV`]: `None` where it is unset or empty, an error
    /// naming the variable and the accepted values where it is something else.
    pub fn from_env() -> Result<Option<Self>, String> {
        match std::env::var(Self::ENV) {
            Err(std::env::VarError::NotPresent) => Ok(None),
            Ok(s) if s.trim().is_empty() => Ok(None),
            Ok(s) => s
                .trim()
                .parse()
                .map(Some)
                .map_err(|e| format!("{}: {e}", Self::ENV)),
            Err(std::env::VarError::NotUnicode(_)) => Err(format!(
                "{}: not valid UTF-8 (expected baseline, avx2 or avx512)",
                Self::ENV
            )),
        }
    }

    /// Narrowest first.
    const ALL: [Self; 3] = [Self::Baseline, Self::Avx2, Self::Avx512];

    /// How many runs a batch of lanes holds on these instructions: one register per value
    /// (eight on AVX-512, four on AVX2; two on the baseline target, where four lanes measured
    /// slower: `benches/lanes.rs`).
    pub fn lanes(self) -> usize {
        match self {
            Self::Baseline => 2,
            Self::Avx2 => 4,
            Self::Avx512 => 8,
        }
    }
}

impl std::str::FromStr for Instructions {
    type Err = String;

    /// `baseline`, `avx2` or `avx512` (any case), as [`Instructions`]' `Display` writes them.
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|i| i.to_string().eq_ignore_ascii_case(s))
            .ok_or_else(|| format!("`{s}` is not one of baseline, avx2, avx512"))
    }
}

impl std::fmt::Display for Instructions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Baseline => "baseline",
            Self::Avx2 => "avx2",
            Self::Avx512 => "avx512",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instructions_read_write_and_size_batches() {
        for i in Instructions::ALL {
            assert_eq!(i.to_string().parse::<Instructions>(), Ok(i));
            assert_eq!(i.to_string().to_uppercase().parse::<Instructions>(), Ok(i));
        }
        assert!(
            "sse2"
                .parse::<Instructions>()
                .unwrap_err()
                .contains("`sse2`")
        );
        assert!(Instructions::Baseline < Instructions::Avx2);
        assert!(Instructions::Avx2 < Instructions::Avx512);
        let lanes = Instructions::ALL.map(Instructions::lanes);
        assert_eq!(lanes, [2, 4, 8]);
        // The instructions used are never wider than the CPU's.
        assert!(Instructions::detected() <= Instructions::cpu());
    }
}
