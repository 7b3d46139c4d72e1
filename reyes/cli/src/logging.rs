//! The command-line tools' diagnostics (`reyes`, `schedbench`): `log` records written to stderr
//! by `env_logger`. `RUST_LOG` picks what is shown (env_logger's syntax: `RUST_LOG=info`,
//! `RUST_LOG=wgpu_hal=debug,naga=info`); without it, warnings and errors of every crate
//! (ours, and wgpu's and naga's own), which a clean run does not print. Records of our
//! crates read `warning: ...` as before; others name their source (`warning [wgpu_hal::...]:`).
//! Each record is written with the progress bars taken off the terminal (`progress::suspend`),
//! so a warning printed while a bar is shown goes above it instead of through it.

use std::io::Write;

/// The filter without `RUST_LOG`.
pub const DEFAULT_FILTER: &str = "warn";

/// The word a record's level is printed as.
pub fn level_word(level: log::Level) -> &'static str {
    match level {
        log::Level::Error => "error",
        log::Level::Warn => "warning",
        log::Level::Info => "info",
        log::Level::Debug => "debug",
        log::Level::Trace => "trace",
    }
}

/// Whether a record comes from this workspace's crates (printed without its source).
fn ours(target: &str) -> bool {
    let krate = target.split("::").next().unwrap_or(target);
    matches!(krate, "reyes" | "scheduler" | "schedbench")
}

/// One record's line.
pub fn format_line(level: log::Level, target: &str, message: &std::fmt::Arguments) -> String {
    if ours(target) {
        format!("{}: {message}", level_word(level))
    } else {
        format!("{} [{target}]: {message}", level_word(level))
    }
}

/// env_logger's logger, writing each record with the progress bars suspended.
struct AboveBars(env_logger::Logger);

impl log::Log for AboveBars {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        self.0.enabled(metadata)
    }

    fn log(&self, record: &log::Record) {
        if self.0.matches(record) {
            crate::progress::suspend(|| self.0.log(record));
        }
    }

    fn flush(&self) {
        self.0.flush();
    }
}

/// Starts the logger (once; later calls do nothing).
pub fn init() {
    let logger =
        env_logger::Builder::from_env(env_logger::Env::default().default_filter_or(DEFAULT_FILTER))
            .format(|buf, r| writeln!(buf, "{}", format_line(r.level(), r.target(), r.args())))
            .build();
    let max = logger.filter();
    if log::set_boxed_logger(Box::new(AboveBars(logger))).is_ok() {
        log::set_max_level(max);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_name_foreign_sources_only() {
        let l = format_line(log::Level::Warn, "reyes", &format_args!("skipped {}", 2));
        assert_eq!(l, "warning: skipped 2");
        let l = format_line(log::Level::Error, "schedbench::suite", &format_args!("x"));
        assert_eq!(l, "error: x");
        let l = format_line(log::Level::Warn, "wgpu_hal::vulkan", &format_args!("y"));
        assert_eq!(l, "warning [wgpu_hal::vulkan]: y");
    }
}
