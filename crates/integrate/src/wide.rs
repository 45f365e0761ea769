//! Whether the stage system's factorisations and solves compiled for AVX2 run: on an x86-64 CPU that
//! has it, unless `SATSIM_INSTRUCTIONS=baseline` caps the kernels to the baseline target
//! (the variable of `satsim_satellite::instructions::Instructions`, which the rigid kernel
//! reads). An AVX2 instance executes the same IEEE operations in the same order as the
//! baseline's (Rust never contracts `a * b + c` into a fused multiply-add, nor reorders a
//! sum); the loops the compiler vectorises take four `f64` an instruction where SSE2 takes
//! two, and VEX's three-operand forms save moves. Both give the same bits.

use std::sync::OnceLock;

/// Whether the AVX2 instances run: decided once per process.
pub(crate) fn avx2() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| {
        cpu_avx2()
            && !std::env::var("SATSIM_INSTRUCTIONS")
                .is_ok_and(|s| s.trim().eq_ignore_ascii_case("baseline"))
    })
}

/// Whether this CPU has AVX2 (the standard library caches the detection): what makes
/// calling an AVX2 instance sound.
#[inline]
pub(crate) fn cpu_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
