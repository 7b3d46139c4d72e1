//! Output files (images, statistics, reports) written whole or not at all: the bytes go to a
//! uniquely named temporary file in the target's folder (`tempfile`), which is renamed over the
//! target at the end. A failure leaves nothing behind, a reader never sees half a file, and two
//! runs writing the same name do not collide (each has its own temporary file).
//!
//! A target that is not a regular file is never replaced: a symbolic link is followed (the
//! file it points to is written, atomically, and the link stays); a character device or a
//! FIFO (`/dev/null`, `/dev/stdout`, a named pipe) is written in place, as a shell's `>`
//! would; anything else (a directory, a block device, a socket) is refused with an error
//! naming the path.

use crate::Error;
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically; through a symbolic link to the file it points to, and
/// in place to a character device or a FIFO (module documentation). Errors name the path:
/// [`Error::Write`] (a missing or read-only folder, a full disk, a target that is neither a
/// file nor a device or FIFO, a cycle of links), [`Error::NotAFileName`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let err = |source: std::io::Error| Error::Write {
        path: path.to_path_buf(),
        source,
    };
    let target = match resolve_links(path).map_err(err)? {
        Target::Regular(p) => p,
        Target::InPlace => {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(err)?;
            return f.write_all(bytes).and_then(|()| f.flush()).map_err(err);
        }
    };
    if target != path {
        return write_atomic(&target, bytes);
    }
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

/// Where [`write_atomic`] writes.
enum Target {
    /// A regular file, or no file yet: this path (links followed), replaced atomically.
    Regular(std::path::PathBuf),
    /// A character device or a FIFO: written in place.
    InPlace,
}

/// Follows `path`'s symbolic links (up to 40, as the kernel does) to what they name, which may
/// not exist yet (a dangling link names the file to create); refuses what is neither a regular
/// file nor a character device or FIFO.
fn resolve_links(path: &Path) -> std::io::Result<Target> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        let meta = match std::fs::symlink_metadata(&p) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Target::Regular(p)),
            Err(e) => return Err(e),
        };
        let t = meta.file_type();
        if t.is_symlink() {
            let to = std::fs::read_link(&p)?;
            p = match p.parent() {
                Some(dir) if to.is_relative() => dir.join(to),
                _ => to,
            };
            continue;
        }
        if t.is_file() {
            return Ok(Target::Regular(p));
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if t.is_char_device() || t.is_fifo() {
                return Ok(Target::InPlace);
            }
        }
        let what = if t.is_dir() {
            "a directory"
        } else {
            "not a regular file, character device or FIFO"
        };
        return Err(std::io::Error::other(format!(
            "{what}: not replaced by an output file"
        )));
    }
    Err(std::io::Error::other(
        "more than 40 symbolic links (a cycle?)",
    ))
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

    /// A symbolic link is followed (the file it points to written, the link kept); a FIFO and
    /// a character device are written in place, never replaced by a regular file; a
    /// directory is refused (a special file must never become a regular one).
    #[cfg(unix)]
    #[test]
    fn special_targets_are_written_in_place_or_refused_never_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("real.png");
        std::fs::write(&file, b"old").unwrap();
        let link = dir.path().join("link.png");
        std::os::unix::fs::symlink("real.png", &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
        assert_eq!(std::fs::read(&file).unwrap(), b"new");
        // A dangling link names the file to create.
        let dangling = dir.path().join("dangling.png");
        std::os::unix::fs::symlink("made.png", &dangling).unwrap();
        write_atomic(&dangling, b"made").unwrap();
        assert!(std::fs::symlink_metadata(&dangling).unwrap().is_symlink());
        assert_eq!(std::fs::read(dir.path().join("made.png")).unwrap(), b"made");
        // A cycle of links is an error, not a loop.
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        std::os::unix::fs::symlink("b", &a).unwrap();
        std::os::unix::fs::symlink("a", &b).unwrap();
        assert!(write_atomic(&a, b"x").is_err());

        let fifo = dir.path().join("pipe.png");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            let reader = {
                let fifo = fifo.clone();
                std::thread::spawn(move || std::fs::read(fifo).unwrap())
            };
            write_atomic(&fifo, b"through the pipe").unwrap();
            assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
            assert_eq!(reader.join().unwrap(), b"through the pipe");
        }

        let null = Path::new("/dev/null");
        if std::fs::metadata(null).is_ok_and(|m| m.file_type().is_char_device()) {
            write_atomic(null, b"discarded").unwrap();
            assert!(
                std::fs::metadata(null)
                    .unwrap()
                    .file_type()
                    .is_char_device()
            );
        }

        let sub = dir.path().join("folder");
        std::fs::create_dir(&sub).unwrap();
        let e = write_atomic(&sub, b"x").unwrap_err().to_string();
        assert!(e.contains("folder") && e.contains("directory"), "{e}");
        assert!(sub.is_dir());
    }
}
