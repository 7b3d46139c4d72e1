//! `measure`: the measurement entry point. Runs named suites (trees, frames, bench, effects,
//! ...) with the built `schedbench` and `reyes` commands, reads their JSON outputs and prints
//! one table: per suite, case and strategy the GPU ms median ± MAD, the wall ms median, the
//! timed runs and whether the results were verified. With `--compare DIR` a second build runs
//! as the baseline, alternated with the first process by process, and the table gives their
//! ratio. docs/results.md ("How to measure") describes the suites and the device set-up.
//!
//! cargo build --release --bin measure --bin schedbench --bin reyes
//! target/release/measure trees frames --runs 10
//! target/release/measure frames --compare ../before/release --out ab/

#[path = "../measure/mod.rs"]
mod measure;

use clap::{CommandFactory, Parser};
use measure::cli::Cli;
use measure::error::Error;
use measure::plan::{self, Case, PlanInput, Program};
use measure::read::read;
use measure::run::{self, Build, Runner};
use measure::table::Table;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

/// Each case's program in each build: `None` where that build lacks a test binary.
type Programs = Vec<Vec<(Build, Option<PathBuf>)>>;

/// Finds every case's program in the builds. Errors name a missing `schedbench` or `reyes`,
/// or every test binary looked for when none is there.
fn find_programs(cases: &[Case], builds: &[(Build, PathBuf)]) -> Result<Programs, Error> {
    let mut found = Vec::new();
    for case in cases {
        let mut per_build = Vec::new();
        for (build, dir) in builds {
            let exe = run::find_program(dir, case.program);
            if exe.is_none() && !matches!(case.program, Program::Test(_)) {
                let flag = match build {
                    Build::New => "--bin",
                    Build::Base => "--compare",
                };
                return Err(Error::MissingProgram {
                    program: case.program.to_string(),
                    dir: dir.clone(),
                    flag,
                });
            }
            per_build.push((*build, exe));
        }
        found.push(per_build);
    }
    let tests: Vec<usize> = (0..cases.len())
        .filter(|&i| matches!(cases[i].program, Program::Test(_)))
        .collect();
    if !tests.is_empty()
        && tests
            .iter()
            .all(|&i| found[i].iter().all(|b| b.1.is_none()))
    {
        let dirs: Vec<String> = builds.iter().map(|b| b.1.display().to_string()).collect();
        return Err(Error::NoTestBinaries {
            tests: plan::GPU_TESTS.join(", "),
            dirs: dirs.join(" or "),
        });
    }
    for &i in &tests {
        for (build, exe) in &found[i] {
            if exe.is_none() {
                eprintln!(
                    "measure: {} not in the {} build: skipped there",
                    cases[i].program,
                    build.name()
                );
            }
        }
    }
    Ok(found)
}

/// Runs every case and returns the table; writes each case's command line into
/// `commands.txt` and each image's md5 into `md5.txt` in the work folder.
fn run_all(cli: &Cli, cases: &[Case], programs: &Programs, runner: &Runner) -> Table {
    let mut table = Table {
        compare: cli.compare.is_some(),
        ..Table::default()
    };
    let mut commands = String::new();
    let mut md5 = String::new();
    let repeats = cli.repeats();
    let total: usize = cases
        .iter()
        .zip(programs)
        .map(|(c, p)| {
            let builds = p.iter().filter(|b| b.1.is_some()).count();
            if c.reference {
                1
            } else {
                builds * repeats as usize
            }
        })
        .sum();
    let mut n = 0;
    for (i, (case, builds)) in cases.iter().zip(programs).enumerate() {
        let builds: Vec<(Build, &Path)> = builds
            .iter()
            .filter_map(|(b, exe)| Some((*b, exe.as_deref()?)))
            .filter(|(b, _)| !case.reference || *b == Build::New)
            .collect();
        for (b, exe) in &builds {
            commands += &format!(
                "{} {}: {}\n",
                b.name(),
                case.name,
                run::command_line(exe, case)
            );
        }
        let reps = if case.reference { 1 } else { repeats };
        for rep in 1..=reps {
            for &(build, exe) in &builds {
                n += 1;
                let strategy = case
                    .strategy
                    .as_deref()
                    .map_or(String::new(), |s| format!(" {s}"));
                eprint!(
                    "measure: [{n}/{total}] {} {}{strategy} ({}, {rep}/{reps}) ... ",
                    case.suite.name(),
                    case.name,
                    build.name()
                );
                let p = runner.run(i, case, exe, build, rep);
                match p.failure() {
                    None => eprintln!("{:.1} s", p.seconds),
                    Some(why) => eprintln!("{:.1} s, failed: {why}", p.seconds),
                }
                let samples = read(case, &p);
                if let (Some(image), Some(m)) =
                    (&p.image, samples.first().and_then(|s| s.md5.clone()))
                {
                    let name = image.file_name().unwrap_or_default().to_string_lossy();
                    md5 += &format!("{m}  {}/{name}\n", case.suite.name());
                }
                if let Some(image) = p.image.as_ref().filter(|_| !cli.keep_images) {
                    // Hashed; scratch space is not kept.
                    let _ = std::fs::remove_file(image);
                }
                table.add(case, build, samples);
            }
        }
    }
    let write = |name: &str, text: &str| {
        if let Err(e) = std::fs::write(runner.work.join(name), text) {
            eprintln!("measure: writing {name}: {e}");
        }
    };
    write("commands.txt", &commands);
    if !md5.is_empty() {
        write("md5.txt", &md5);
    }
    table.finish();
    table
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    cli.check();
    match measure(&cli) {
        // The table could not be written (reported when it failed).
        Ok(true) if reyes_cli::stdout::failed() => ExitCode::FAILURE,
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("measure: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Ok(true) when every process succeeded and every checked row was verified.
fn measure(cli: &Cli) -> Result<bool, Error> {
    let new_dir = match &cli.bin {
        Some(d) => d.clone(),
        None => std::env::current_exe()
            .map_err(Error::CurrentExe)?
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default(),
    };
    let mut builds = Vec::new();
    if let Some(base) = &cli.compare {
        builds.push((Build::Base, base.clone()));
    }
    builds.push((Build::New, new_dir));
    let data = cli.data.clone().unwrap_or_else(reyes::shared_data_dir);
    let scratch = tempfile::tempdir().map_err(Error::ScratchFolder)?;
    let temporary_work;
    let work = match &cli.out {
        Some(out) => {
            std::fs::create_dir_all(out).map_err(|source| Error::CreateFolder {
                path: out.clone(),
                source,
            })?;
            out.clone()
        }
        None => {
            temporary_work = tempfile::tempdir().map_err(Error::WorkFolder)?;
            temporary_work.path().to_path_buf()
        }
    };
    let input = PlanInput {
        size: cli.size,
        runs: cli.runs,
        scenes: &cli.scenes,
        data: &data,
        scratch: scratch.path(),
    };
    let cases = plan::select(plan::plan(&cli.suites, &input)?, &cli.only);
    if cases.is_empty() {
        Cli::command()
            .error(
                clap::error::ErrorKind::InvalidValue,
                format!(
                    "--only {}: no case of these suites matches",
                    cli.only.join(", ")
                ),
            )
            .exit();
    }
    let programs = find_programs(&cases, &builds)?;
    let mut env: Vec<(String, OsString)> =
        vec![("REYES_SHARED_DATA".into(), data.clone().into_os_string())];
    if let Some(a) = &cli.adapter {
        env.push(("WGPU_ADAPTER_NAME".into(), a.into()));
    }
    let runner = Runner {
        work: work.clone(),
        scratch: scratch.path().to_path_buf(),
        keep_images: cli.keep_images,
        timeout: Duration::from_secs(cli.timeout),
        env,
    };
    let table = run_all(cli, &cases, &programs, &runner);
    let labels: Vec<(Build, String)> = builds
        .iter()
        .map(|(b, d)| (*b, d.display().to_string()))
        .collect();
    let (text, markdown) = (table.text(&labels), table.markdown(&labels));
    if cli.out.is_some() {
        for (name, t) in [("table.txt", &text), ("table.md", &markdown)] {
            std::fs::write(work.join(name), t).map_err(|source| Error::Write {
                path: work.join(name),
                source,
            })?;
        }
    }
    // Through reyes_cli::stdout, as schedbench and reyes print: a reader that left (`measure
    // ... | head`) ends the output only, the status stays the runs' and --out keeps the table.
    reyes_cli::out!("{}", if cli.markdown { &markdown } else { &text });
    Ok(table.all_good())
}
