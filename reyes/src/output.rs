//! Output files (images, statistics, reports) written whole or not at all: the bytes go to a
//! uniquely named temporary file in the target's folder (`tempfile`), which is renamed over the
//! target at the end. A failure leaves nothing behind, a reader never sees half a file, and two
//! runs writing the same name do not collide (each has its own temporary file).

use crate::Error;
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically. Errors name the path: [`Error::Write`] (a missing or
/// read-only folder, a full disk), [`Error::NotAFileName`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let err = |source: std::io::Error| Error::Write {
        path: path.to_path_buf(),
        source,
    };
    let name = path.file_name().ok_or_else(|| Error::NotAFileName {
        path: path.to_path_buf(),
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!(".{}.", name.to_string_lossy()))
        .suffix(".partial")
        .permissions(new_file_permissions())
        .tempfile_in(dir)
        .map_err(err)?;
    tmp.write_all(bytes).map_err(err)?;
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

/// The permissions an output file is created with: those of any new file (0666 less the
/// umask, e.g. 0644), not the owner-only 0600 that temporary files get by default.
pub fn new_file_permissions() -> std::fs::Permissions {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::Permissions::from_mode(0o666)
    }
    #[cfg(not(unix))]
    {
        // Elsewhere a new file's default: writable, which the metadata of a fresh temp
        // directory's files gives.
        let f = tempfile::tempfile().expect("a temporary file");
        f.metadata().expect("its metadata").permissions()
    }
}

/// An image encoded as PNG, for [`write_atomic`]. Errors: [`Error::Encode`].
pub fn png<P, C>(img: &image::ImageBuffer<P, C>) -> Result<Vec<u8>, Error>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)?;
    Ok(out.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_whole_files_and_leaves_nothing_on_failure() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let missing = dir.path().join("no/such/folder/b.txt");
        let e = write_atomic(&missing, b"x").unwrap_err().to_string();
        assert!(e.contains("no/such/folder/b.txt"), "{e}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only a.txt: no temporary file left");
        // Created as any new file (0666 less the umask), not owner-only as temporary files.
        #[cfg(target_os = "linux")]
        {
            use std::os::unix::fs::PermissionsExt;
            let status = std::fs::read_to_string("/proc/self/status").unwrap();
            let umask = status
                .lines()
                .find_map(|l| l.strip_prefix("Umask:"))
                .map(|v| u32::from_str_radix(v.trim(), 8).unwrap())
                .unwrap();
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o666 & !umask, "mode {mode:o}, umask {umask:o}");
        }
    }
}
