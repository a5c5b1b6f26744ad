//! Output files written whole or not at all. Every file the tool writes (meshlet, LOD and
//! compressed files, glTF exports, PNGs, PLYs, the tables and plots in results/) goes through
//! [`write_with`]: the bytes go to a temporary file in the target's folder, which replaces the
//! target with one rename once it is complete and on disk. A run that fails, panics or is killed
//! midway (Ctrl-C, out of memory, a cancelled CI job) leaves the previous file as it was, never a
//! truncated one; a killed process may leave its temporary file (`.NAME.XXXXXX.tmp`) beside it.

use std::io::{self, Write};
use std::path::Path;

/// Writes `path` with what `fill` writes, atomically (see the module doc). The new file gets the
/// permissions a plain create would give it (0666 less the umask on Unix).
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: not a file name", path.display()),
        )
    })?;
    let prefix = format!(".{}.", name.to_string_lossy());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    // Dropped on any early return: the temporary file is removed, the target untouched.
    let mut tmp = builder.tempfile_in(dir)?;
    {
        let mut w = io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w)?;
        w.flush()?;
    }
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Writes `bytes` to `path` atomically (a drop-in for `std::fs::write`).
pub fn write(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> io::Result<()> {
    write_with(path.as_ref(), |w| w.write_all(bytes.as_ref()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh scratch folder, removed again when the test ends (passed or failed).
    fn scratch(name: &str) -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix(&format!("meshletlab-atomic-{name}-"))
            .tempdir()
            .unwrap()
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn an_interrupted_write_leaves_the_previous_file_intact() {
        let d = scratch("interrupted");
        let p = d.path().join("out.bin");
        write(&p, b"the previous, complete file").unwrap();
        // An error after half the bytes (a full disk, a failed encoder): nothing changes.
        let e = write_with(&p, |w| {
            w.write_all(b"half of the new")?;
            Err(io::Error::other("interrupted"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "interrupted");
        assert_eq!(std::fs::read(&p).unwrap(), b"the previous, complete file");
        // A panic midway (what Ctrl-C or a kill looks like to the file: the rename never runs).
        let r = std::panic::catch_unwind(|| {
            write_with(&p, |w| {
                w.write_all(b"half of the new")?;
                panic!("killed midway")
            })
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"the previous, complete file");
        // No temporary file is left behind by either, and a complete write replaces the file.
        assert_eq!(entries(d.path()), ["out.bin"]);
        write(&p, b"new").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
        assert_eq!(entries(d.path()), ["out.bin"]);
    }

    #[cfg(unix)]
    #[test]
    fn written_files_get_the_usual_permissions() {
        use std::os::unix::fs::PermissionsExt as _;
        let d = scratch("mode");
        let (a, b) = (d.path().join("plain"), d.path().join("atomic"));
        std::fs::write(&a, b"x").unwrap();
        write(&b, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&b), mode(&a));
    }

    #[test]
    fn a_path_without_a_file_name_or_folder_is_an_error() {
        assert!(write(Path::new("/"), b"x").is_err());
        let d = scratch("bare");
        assert!(write(d.path().join("missing/out.bin"), b"x").is_err());
    }
}
