//! Standard output for the commands' tables and JSON records ([`outln!`](crate::outln),
//! [`out!`](crate::out)).
//!
//! `println!` panics when standard output fails, and it fails whenever the reader goes away
//! first (`schedbench ... | head`: the pipe is closed, a write gets `EPIPE`), so such a run
//! ended in a panic and exit 101 where the commands promise 0, 1 or 2. Here a closed pipe
//! only ends the printing: the command finishes its runs, their checks and the files it
//! writes, and exits with the status it would have had, as nothing it was asked to make is
//! lost. Any other write error (a full disk behind `> file`) is reported on standard error
//! once, the rest of the output is dropped, and [`failed`] makes the command exit 1.

use std::fmt;
use std::io::{self, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU8, Ordering};

/// Writing: 0, the pipe closed by its reader: 1, another error: 2.
static STATE: AtomicU8 = AtomicU8::new(0);
const OPEN: u8 = 0;
const CLOSED: u8 = 1;
const FAILED: u8 = 2;

/// Writes `args` to standard output and flushes it, unless an earlier write failed. A
/// closed pipe (`ErrorKind::BrokenPipe`) silences the rest of the output; another error is
/// reported (`COMMAND: standard output: ERROR`, the command as it was called) and silences
/// it too.
pub fn write(args: fmt::Arguments) {
    if STATE.load(Ordering::Relaxed) != OPEN {
        return;
    }
    let mut out = io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.flush()) {
        if e.kind() == io::ErrorKind::BrokenPipe {
            STATE.store(CLOSED, Ordering::Relaxed);
        } else {
            STATE.store(FAILED, Ordering::Relaxed);
            let command = std::env::args_os().next().unwrap_or_default();
            let command = Path::new(&command).file_name().unwrap_or_default();
            eprintln!("{}: standard output: {e}", command.to_string_lossy());
        }
    }
}

/// Whether a write to standard output failed for another reason than a closed pipe: the
/// command's output is incomplete, and it should exit 1.
pub fn failed() -> bool {
    STATE.load(Ordering::Relaxed) == FAILED
}

/// `println!` through [`write()`](crate::stdout::write).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::stdout::write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` through [`write()`](crate::stdout::write).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!($($arg)*))
    };
}
