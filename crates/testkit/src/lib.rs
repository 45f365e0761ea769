//! What the workspace's integration tests share (a dev-dependency of each crate, never
//! published): the counting allocator of the no-allocation tests, fresh temporary folders,
//! the repository's root and the runner of the `satsim` binary.
//!
//! Each crate's tests are one binary, `tests/it/main.rs`, with one module per subject; what
//! only one crate's tests share (models and systems of that crate) is that binary's
//! `tests/it/common.rs`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub mod alloc {
    //! A global allocator that counts the calling thread's allocations: a test binary
    //! installs it once (`#[global_allocator] static A: satsim_testkit::alloc::Counting =
    //! satsim_testkit::alloc::Counting;`) and a test compares [`allocations`] before and
    //! after the section it checks. The count is per thread, so the tests that run in
    //! parallel in the same binary, and the harness's own threads (output capture, the
    //! "running for over 60 seconds" timer), never add to it.

    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    thread_local! {
        static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    }

    fn count() {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    }

    /// The allocations (and reallocations) this thread has made so far.
    pub fn allocations() -> usize {
        ALLOCATIONS.with(|c| c.get())
    }

    /// The system allocator, counting each thread's allocations and reallocations.
    pub struct Counting;

    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            count();
            unsafe { System.alloc(layout) }
        }
        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            unsafe { System.dealloc(ptr, layout) }
        }
        unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
            count();
            unsafe { System.realloc(ptr, layout, new_size) }
        }
    }
}

/// The repository's root (the workspace).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh, empty folder `satsim-{name}-{process id}` under the system's temporary folder
/// (emptied if a previous run left it). `name` tells the tests of one binary apart: the
/// module and the test (`"campaign-seeds"`).
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("satsim-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// [`temp_dir`] with copies of `files` (paths from the repository's root) in it, under their
/// file names: `temp_dir_with("run-x", &["examples/satellite.toml"])`.
pub fn temp_dir_with(name: &str, files: &[&str]) -> PathBuf {
    let dir = temp_dir(name);
    for f in files {
        let from = root().join(f);
        std::fs::copy(&from, dir.join(from.file_name().unwrap()))
            .unwrap_or_else(|e| panic!("copy {}: {e}", from.display()));
    }
    dir
}

/// Runs the program `exe` with `args` in `dir` and waits for it. A test passes its crate's
/// binary: `env!("CARGO_BIN_EXE_satsim")` (known only to the tests of the crate that builds it).
pub fn run_in(exe: &str, dir: &Path, args: &[&str]) -> Output {
    Command::new(exe)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("run {exe}: {e}"))
}

/// The output's standard output, as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The output's standard error, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
