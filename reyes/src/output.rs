//! Output files (images, statistics, reports) written whole or not at all: the bytes go to a
//! uniquely named temporary file in the target's folder (`tempfile`), which is renamed over the
//! target at the end. A failure leaves nothing behind, a reader never sees half a file, and two
//! runs writing the same name do not collide (each has its own temporary file).

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically. Errors name the path: a missing or read-only folder, a
/// full disk.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let err = |e: std::io::Error| format!("{}: {e}", path.display());
    let name = path
        .file_name()
        .ok_or_else(|| format!("{}: not a file name", path.display()))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!(".{}.", name.to_string_lossy()))
        .suffix(".partial")
        .tempfile_in(dir)
        .map_err(err)?;
    tmp.write_all(bytes).map_err(err)?;
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

/// An image encoded as PNG, for [`write_atomic`].
pub fn png<P, C>(img: &image::ImageBuffer<P, C>) -> Result<Vec<u8>, String>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
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
        let e = write_atomic(&missing, b"x").unwrap_err();
        assert!(e.contains("no/such/folder/b.txt"), "{e}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only a.txt: no temporary file left");
    }
}
