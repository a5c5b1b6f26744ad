//! Helpers shared by the integration tests.
#![allow(dead_code)]

use meshletlab::mesh::{self, Mesh};
use std::path::PathBuf;
use std::process::{Command, Output};

/// The shared real meshes: $MESHLETLAB_MESHES or ../shared/meshes next to the repository.
pub fn meshes_dir() -> PathBuf {
    let dir = std::env::var_os("MESHLETLAB_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes"));
    assert!(
        dir.join("SOURCES.md").is_file(),
        "real test meshes not found in {} (set MESHLETLAB_MESHES); these tests must not silently pass without them",
        dir.display()
    );
    dir
}

/// All shared mesh files, sorted by name.
pub fn mesh_files() -> Vec<PathBuf> {
    let files = meshletlab::bench::build::mesh_files(&meshes_dir()).expect("mesh folder lists");
    assert_eq!(files.len(), 10, "expected the ten shared meshes");
    files
}

/// Loads one shared mesh by stem, e.g. "stanford_bunny".
pub fn load(stem: &str) -> Mesh {
    mesh::load(&meshes_dir().join(format!("{stem}.ply.zst"))).expect("shared mesh loads")
}

/// A rayon pool of exactly `n` threads. Thread-count tests compare explicit pools of 1 and
/// [`MANY_THREADS`], never a pool with the global one (on a one-core host both are one thread,
/// and such a test would pass without comparing anything).
pub fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

/// More threads than CI's two cores: work is split differently from the one-thread run.
pub const MANY_THREADS: usize = 4;

/// A unique scratch folder for one test, removed when dropped (whether the test passed or not),
/// so test runs leave nothing in the system temp folder. Derefs to its path.
pub struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        self.0.path()
    }
}

impl AsRef<std::path::Path> for Scratch {
    fn as_ref(&self) -> &std::path::Path {
        self.0.path()
    }
}

/// A fresh [`Scratch`] folder named after the test.
pub fn scratch(name: &str) -> Scratch {
    Scratch(
        tempfile::Builder::new()
            .prefix(&format!("meshletlab-test-{name}-"))
            .tempdir()
            .unwrap(),
    )
}

/// Runs the `meshletlab` binary with `args`.
pub fn cli(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_meshletlab"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// [`cli`] that must succeed; its stdout.
pub fn ok(args: &[&str]) -> String {
    let out = cli(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}
