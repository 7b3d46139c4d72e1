//! Running the cases: finding each build's programs, one process per case, build and
//! repetition (the builds alternated case by case, so that both see the same machine state),
//! stdout and stderr into files, a time limit per process.

use super::plan::{Arg, Case, Program, Reader};
use std::ffi::OsString;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// Which build a process ran.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Build {
    /// `--compare`'s, the baseline.
    Base,
    /// `--bin`'s, the build under test.
    New,
}

impl Build {
    /// `base` or `new`, as the table and the file names say.
    pub fn name(self) -> &'static str {
        match self {
            Build::Base => "base",
            Build::New => "new",
        }
    }
}

/// The executable of `program` in `dir`: `dir/NAME`, or for a test binary cargo's
/// `dir/deps/NAME-HASH` (the newest).
pub fn find_program(dir: &Path, program: Program) -> Option<PathBuf> {
    let exe = std::env::consts::EXE_SUFFIX;
    let plain = dir.join(format!("{}{exe}", program.name()));
    if plain.is_file() {
        return Some(plain);
    }
    let Program::Test(name) = program else {
        return None;
    };
    let is_hashed = |file: &str| {
        file.strip_suffix(exe)
            .and_then(|f| f.strip_prefix(name))
            .and_then(|f| f.strip_prefix('-'))
            .is_some_and(|hash| hash.len() == 16 && hash.chars().all(|c| c.is_ascii_hexdigit()))
    };
    std::fs::read_dir(dir.join("deps"))
        .ok()?
        .filter_map(Result::ok)
        .filter(|e| is_hashed(&e.file_name().to_string_lossy()))
        .filter_map(|e| Some((e.metadata().ok()?.modified().ok()?, e.path())))
        .max()
        .map(|(_, p)| p)
}

/// How a process ended.
#[derive(Debug)]
pub enum Ended {
    Exited(ExitStatus),
    /// Stopped at the time limit.
    TimedOut(Duration),
    /// Could not be started.
    NotStarted(String),
}

/// One process of a case: its files and how it ended.
#[derive(Debug)]
pub struct Process {
    /// The stem of this process's files (`Arg::Out`), and its stdout and stderr.
    pub stem: PathBuf,
    pub stdout: PathBuf,
    pub stderr: PathBuf,
    /// The image it was asked to write (`Arg::Image`).
    pub image: Option<PathBuf>,
    pub ended: Ended,
    /// Process wall time.
    pub seconds: f64,
}

impl Process {
    /// A one-line reason when the process did not exit with status 0.
    pub fn failure(&self) -> Option<String> {
        match &self.ended {
            Ended::Exited(s) if s.success() => None,
            Ended::Exited(s) => Some(format!("{s}{}", last_line(&self.stderr))),
            Ended::TimedOut(limit) => Some(format!("stopped after {} s", limit.as_secs())),
            Ended::NotStarted(e) => Some(e.clone()),
        }
    }

    /// The exit code, when it exited.
    pub fn code(&self) -> Option<i32> {
        match &self.ended {
            Ended::Exited(s) => s.code(),
            _ => None,
        }
    }
}

/// `: LINE` for the last non-empty line of a file, else empty.
fn last_line(file: &Path) -> String {
    let text = std::fs::read_to_string(file).unwrap_or_default();
    text.lines()
        .rev()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .map_or(String::new(), |l| format!(": {l}"))
}

/// Where processes put their files and what they run with.
pub struct Runner {
    /// Output folder (`--out` or a temporary one).
    pub work: PathBuf,
    /// Scratch folder (generated scenes, references, images not kept).
    pub scratch: PathBuf,
    pub keep_images: bool,
    pub timeout: Duration,
    /// Environment for every process (`WGPU_ADAPTER_NAME`, `REYES_SHARED_DATA`).
    pub env: Vec<(String, OsString)>,
}

/// A file name part: letters, digits, `.`, the rest `-`.
fn slug(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' {
                c
            } else {
                '-'
            }
        })
        .collect()
}

impl Runner {
    /// Runs `case` (number `index` of the plan) once with `exe`.
    pub fn run(&self, index: usize, case: &Case, exe: &Path, build: Build, rep: u32) -> Process {
        let suite = case.suite.name();
        let name = format!(
            "{index:03}-{}{}-{}-{rep}",
            slug(&case.name),
            case.strategy
                .as_deref()
                .map_or(String::new(), |s| format!("-{}", slug(s))),
            build.name()
        );
        let stem = self.work.join(&suite).join(&name);
        let image_dir = if self.keep_images {
            &self.work
        } else {
            &self.scratch
        };
        let image = image_dir.join(&suite).join(format!("{name}.png"));
        let stdout_ext = match case.reader {
            Reader::Schedbench => "jsonl",
            Reader::Bench { .. } => "json",
            _ => "txt",
        };
        // Pushed, not `with_extension`: case names may hold dots (`mp 0.5`).
        let with = |suffix: &str| {
            let mut p = stem.clone().into_os_string();
            p.push(suffix);
            PathBuf::from(p)
        };
        let stdout = with(&format!(".{stdout_ext}"));
        let stderr = with(".log");
        let mut uses_image = false;
        let args: Vec<OsString> = case
            .args
            .iter()
            .map(|a| match a {
                Arg::Lit(s) => s.clone(),
                Arg::Out(suffix) => with(suffix).into_os_string(),
                Arg::Image => {
                    uses_image = true;
                    image.clone().into_os_string()
                }
            })
            .collect();
        let mut process = Process {
            stdout,
            stderr,
            image: uses_image.then_some(image),
            stem,
            ended: Ended::NotStarted(String::new()),
            seconds: 0.0,
        };
        let start = Instant::now();
        process.ended = self.spawn_and_wait(exe, &args, &process);
        process.seconds = start.elapsed().as_secs_f64();
        process
    }

    fn spawn_and_wait(&self, exe: &Path, args: &[OsString], p: &Process) -> Ended {
        let parents = [p.stem.parent(), p.image.as_deref().and_then(Path::parent)];
        for dir in parents.into_iter().flatten() {
            if let Err(e) = std::fs::create_dir_all(dir) {
                return Ended::NotStarted(format!("creating {}: {e}", dir.display()));
            }
        }
        let files = File::create(&p.stdout).and_then(|o| Ok((o, File::create(&p.stderr)?)));
        let (out, err) = match files {
            Ok(f) => f,
            Err(e) => return Ended::NotStarted(format!("creating {}: {e}", p.stdout.display())),
        };
        let child = Command::new(exe)
            .args(args)
            .envs(self.env.iter().map(|(k, v)| (k, v)))
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err)
            .spawn();
        let mut child = match child {
            Ok(c) => c,
            Err(e) => return Ended::NotStarted(format!("starting {}: {e}", exe.display())),
        };
        let start = Instant::now();
        loop {
            match child.try_wait() {
                Ok(Some(status)) => return Ended::Exited(status),
                Ok(None) if start.elapsed() >= self.timeout => {
                    // Stopping our own child; it may have exited in between.
                    let _ = child.kill();
                    let _ = child.wait();
                    return Ended::TimedOut(self.timeout);
                }
                Ok(None) => std::thread::sleep(Duration::from_millis(20)),
                Err(e) => return Ended::NotStarted(format!("waiting for {}: {e}", exe.display())),
            }
        }
    }
}

/// The command line of a process, for the log: program and arguments, shell-quoted where
/// needed.
pub fn command_line(exe: &Path, case: &Case) -> String {
    let mut parts = vec![exe.display().to_string()];
    for a in &case.args {
        parts.push(match a {
            Arg::Lit(s) => {
                let s = s.to_string_lossy();
                if s.is_empty() || s.contains(|c: char| c.is_whitespace() || c == '"') {
                    format!("'{s}'")
                } else {
                    s.into_owned()
                }
            }
            Arg::Out(suffix) => format!("OUT{suffix}"),
            Arg::Image => "OUT.png".into(),
        });
    }
    parts.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test_binaries_are_found_under_cargos_hashed_names() {
        let dir = tempfile::tempdir().unwrap();
        let deps = dir.path().join("deps");
        std::fs::create_dir(&deps).unwrap();
        let exe = std::env::consts::EXE_SUFFIX;
        for f in [
            format!("scheduler_gpu-0123456789abcdef{exe}"),
            "scheduler_gpu-0123456789abcdef.d".to_string(),
            format!("scheduler_gpu_extra-0123456789abcdef{exe}"),
        ] {
            std::fs::write(deps.join(f), "").unwrap();
        }
        let found = find_program(dir.path(), Program::Test("scheduler_gpu")).unwrap();
        assert_eq!(
            found.file_name().unwrap().to_string_lossy(),
            format!("scheduler_gpu-0123456789abcdef{exe}")
        );
        assert_eq!(find_program(dir.path(), Program::Test("reyes_gpu")), None);
        assert_eq!(find_program(dir.path(), Program::Reyes), None);
        std::fs::write(dir.path().join(format!("reyes{exe}")), "").unwrap();
        assert!(find_program(dir.path(), Program::Reyes).is_some());
    }

    #[test]
    fn file_names_keep_letters_digits_and_dots() {
        assert_eq!(slug("motion interleave:2 4x4"), "motion-interleave-2-4x4");
        assert_eq!(slug("mp 0.5"), "mp-0.5");
    }
}
