//! The preprint satellite's tests: one binary (one link), one module per subject; `common`
//! holds the generator and the random preprint models.

mod common;
mod kernel;
mod preprint_cross_check;
mod preprint_formulas;
mod preprint_lagrange;

// `kernel::the_entry_gives_the_kernels_or_the_generic_result_bit_for_bit` counts the
// allocations of its per-call path (per thread: the other tests run in parallel threads).
#[global_allocator]
static GLOBAL: satsim_testkit::alloc::Counting = satsim_testkit::alloc::Counting;
