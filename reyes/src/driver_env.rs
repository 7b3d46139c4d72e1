//! The process environment Mesa's Vulkan drivers expect. On a machine without a login session
//! (a container, CI, ssh without systemd) `XDG_RUNTIME_DIR` is unset, and lavapipe prints
//! "error: XDG_RUNTIME_DIR is invalid or not set in the environment" twice when wgpu creates its
//! instance, although nothing is wrong: the variable only names a folder for per-user runtime
//! files. The command-line tools set it to a private folder of their own when it is unset or
//! names no folder, so a user sees no false error.

/// Makes `XDG_RUNTIME_DIR` name a folder: left alone when it already does; else a private one
/// (mode 0700) under the temporary folder, `reyes-runtime-<uid>`, is made if needed and set.
/// Call first in `main`, before any other thread exists (setting a variable is not
/// thread-safe). Does nothing off Unix; failures leave the variable as it was.
#[allow(
    unsafe_code,
    reason = "std::env::set_var, called first in main while the process has one thread"
)]
pub fn ensure_xdg_runtime_dir() {
    #[cfg(unix)]
    {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt};
        let set = std::env::var_os("XDG_RUNTIME_DIR");
        if set.is_some_and(|d| std::path::Path::new(&d).is_dir()) {
            return;
        }
        let uid = std::fs::metadata("/proc/self").map_or(0, |m| m.uid());
        let dir = std::env::temp_dir().join(format!("reyes-runtime-{uid}"));
        let made = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        let ours = std::fs::metadata(&dir).is_ok_and(|m| m.is_dir() && m.uid() == uid);
        if (made.is_ok() || dir.is_dir()) && ours {
            // SAFETY: called first in `main`, while the process has a single thread.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}
