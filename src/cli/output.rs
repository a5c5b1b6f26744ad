//! What every command shares about its output: text on stdout that survives a reader who leaves
//! early (`| head`), and output paths checked before the work starts, so that a long run never
//! ends on a name it cannot write.

use anyhow::{bail, Context, Result};
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once stdout refused a write: the reader is gone, so the rest of the text is dropped.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes one line to stdout (the `say!` macro). A closed pipe is not an error: the command goes
/// on quietly, writes every file it was asked for, and exits 0.
pub fn line(args: std::fmt::Arguments) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if out
        .write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .is_err()
    {
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
    }
}

/// The file name's lowercase suffix check: `a.PLY.zst` ends in `.ply.zst`.
fn ends_in(path: &Path, ext: &str) -> bool {
    path.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.to_ascii_lowercase().ends_with(&format!(".{ext}")))
}

/// Checks, before any work, that `path` can be written as `what` (e.g. "a PNG"): its name ends in
/// one of `extensions` (none: any name), it is not a directory, its folder exists, and a file can
/// be created there.
pub fn check_file(path: &Path, what: &str, extensions: &[&str]) -> Result<()> {
    if path.is_dir() {
        bail!("{}: is a directory", path.display());
    }
    if !extensions.is_empty() && !extensions.iter().any(|e| ends_in(path, e)) {
        let names: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
        bail!(
            "{}: this writes {what}: name the file {}",
            path.display(),
            names.join(" or ")
        );
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        bail!(
            "{}: cannot write: the folder {} does not exist",
            path.display(),
            folder.display()
        );
    }
    probe(folder).with_context(|| format!("{}: cannot write", path.display()))
}

/// Creates the folder `dir` (and its parents) and checks that files can be written in it.
pub fn check_dir(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        bail!("{}: not a directory", dir.display());
    }
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    probe(dir).with_context(|| format!("{}: cannot write", dir.display()))
}

/// Creates and removes a scratch file in `dir`; the error is the system's, without the scratch
/// file's name.
fn probe(dir: &Path) -> std::io::Result<()> {
    tempfile::Builder::new()
        .prefix(".meshletlab-probe")
        .tempfile_in(dir)
        .map(drop)
        .map_err(|e| match e.raw_os_error() {
            Some(code) => std::io::Error::from_raw_os_error(code),
            None => std::io::Error::from(e.kind()),
        })
}

/// A name for each input, for the files a command writes about it: the file name without its
/// mesh extensions (`bunny.ply.zst` -> `bunny`), or `gen:NAME` -> `NAME`; inputs that share a
/// name get `-2`, `-3`, ... in the order given.
pub fn stems(inputs: &[&Path]) -> Vec<String> {
    let mut seen = std::collections::HashMap::<String, usize>::new();
    inputs
        .iter()
        .map(|p| {
            let base = stem(p);
            let n = seen.entry(base.clone()).or_insert(0);
            *n += 1;
            if *n == 1 {
                base
            } else {
                format!("{base}-{n}")
            }
        })
        .collect()
}

/// One input's stem (see [`stems`]).
fn stem(path: &Path) -> String {
    let s = path.to_string_lossy();
    if let Some(g) = s.strip_prefix("gen:") {
        return g.to_string();
    }
    let mut name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into());
    for ext in [".zst", ".ply", ".obj", ".stl", ".gltf", ".glb"] {
        if name.len() > ext.len() && name.to_ascii_lowercase().ends_with(ext) {
            name.truncate(name.len() - ext.len());
        }
    }
    name
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stems_drop_mesh_extensions_and_number_repeats() {
        let p = |s: &str| Path::new(s).to_path_buf();
        let inputs = [
            p("/a/bunny.ply.zst"),
            p("/b/bunny.PLY"),
            p("gen:sphere"),
            p("x/p.glb"),
            p("c/bunny.obj"),
        ];
        let refs: Vec<&Path> = inputs.iter().map(|x| x.as_path()).collect();
        assert_eq!(stems(&refs), ["bunny", "bunny-2", "sphere", "p", "bunny-3"]);
    }

    #[test]
    fn output_paths_are_checked_before_the_work() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("a.png");
        check_file(&png, "a PNG", &["png"]).unwrap();
        let e = check_file(&dir.path().join("a.jpg"), "a PNG", &["png"]).unwrap_err();
        assert!(e.to_string().contains("name the file .png"), "{e}");
        let e = check_file(dir.path(), "a PNG", &[]).unwrap_err();
        assert!(e.to_string().ends_with("is a directory"), "{e}");
        let e = check_file(&dir.path().join("no/a.png"), "a PNG", &["png"]).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        let sub = dir.path().join("x/y");
        check_dir(&sub).unwrap();
        assert!(sub.is_dir());
        std::fs::write(dir.path().join("f"), b"").unwrap();
        assert!(check_dir(&dir.path().join("f")).is_err());
    }
}
