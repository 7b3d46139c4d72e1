//! Report files written whole or not at all: each is written to a temporary file in the
//! target folder (`tempfile`, removed if anything fails) and renamed over its name at the end.

use crate::error::Error;
use std::io::Write;
use std::path::{Path, PathBuf};
use tempfile::NamedTempFile;

/// A file being written in `dir`; it appears under its name only at [`PendingFile::finish`].
pub struct PendingFile {
    tmp: NamedTempFile,
    path: PathBuf,
}

impl PendingFile {
    pub fn new(dir: &Path, name: &str) -> Result<PendingFile, Error> {
        let tmp = tempfile::Builder::new()
            .prefix(&format!(".{name}."))
            .suffix(".partial")
            .permissions(reyes::output::new_file_permissions())
            .tempfile_in(dir)
            .map_err(|source| Error::File {
                path: dir.to_path_buf(),
                source,
            })?;
        Ok(PendingFile {
            tmp,
            path: dir.join(name),
        })
    }

    pub fn write(&mut self, bytes: &[u8]) -> Result<(), Error> {
        self.tmp.write_all(bytes).map_err(|source| Error::File {
            path: self.path.clone(),
            source,
        })
    }

    /// Flushes to disk and renames the file to its name.
    pub fn finish(self) -> Result<PathBuf, Error> {
        let path = self.path;
        let file_error = |source| Error::File {
            path: path.clone(),
            source,
        };
        self.tmp.as_file().sync_all().map_err(file_error)?;
        self.tmp.persist(&path).map_err(|e| file_error(e.error))?;
        Ok(path)
    }
}

/// Writes `bytes` as `dir/name` through a temporary file.
pub fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, Error> {
    let mut f = PendingFile::new(dir, name)?;
    f.write(bytes)?;
    f.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_appears_only_when_finished() {
        let dir = tempfile::tempdir().unwrap();
        let mut f = PendingFile::new(dir.path(), "a.txt").unwrap();
        f.write(b"half").unwrap();
        assert!(!dir.path().join("a.txt").exists());
        drop(f); // a failure before finish: nothing is left behind
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        write_file(dir.path(), "a.txt", b"whole").unwrap();
        assert_eq!(std::fs::read(dir.path().join("a.txt")).unwrap(), b"whole");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
