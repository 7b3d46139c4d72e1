//! What each suite runs: the suites turned into [`Case`]s, one command line of `schedbench`,
//! `reyes` or a test binary each, with the files it writes and how its output is read. The
//! commands are those the figures of docs/results.md were measured with; `--size small`
//! shrinks the problems, never the kind of run.

use super::cli::{Size, Suite};
use super::error::Error;
use std::ffi::OsString;
use std::fmt;
use std::path::{Path, PathBuf};

/// A program of a build.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Program {
    /// The scheduler's benchmark command.
    Schedbench,
    /// The renderer's command.
    Reyes,
    /// A test binary (cargo's target name, e.g. `scheduler_gpu`).
    Test(&'static str),
}

impl Program {
    /// The file name without the platform's executable suffix.
    pub fn name(self) -> &'static str {
        match self {
            Program::Schedbench => "schedbench",
            Program::Reyes => "reyes",
            Program::Test(name) => name,
        }
    }
}

impl fmt::Display for Program {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The GPU test binaries `gpu-tests` runs when --bin has them.
pub const GPU_TESTS: [&str; 4] = [
    "scheduler_gpu",
    "workloads_gpu",
    "reyes_gpu",
    "reyes_realtime",
];

/// One argument of a case's command line.
#[derive(Debug, Clone, PartialEq)]
pub enum Arg {
    /// As written.
    Lit(OsString),
    /// A file of this process: its stem (folder, case, strategy, build, repetition) with this
    /// suffix (`.json`, or `""` for a folder).
    Out(&'static str),
    /// An image of this process (`.png`): kept in the output folder with `--keep-images`, else
    /// in the scratch folder.
    Image,
}

/// How a process's results are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reader {
    /// `schedbench --json` on stdout: one record per timed run, any strategies.
    Schedbench,
    /// `schedbench --suite`'s `runs.jsonl` in the folder given as `Arg::Out("")`.
    SuiteReport,
    /// `reyes render --stats` (`Arg::Out(".json")`) and its image.
    Render,
    /// `reyes bench --json` on stdout; with `peer`, a second row for the raster peer.
    Bench { peer: bool },
    /// The test harness's `test result:` lines on stdout.
    Tests,
    /// Nothing but the exit status and the process time (`reyes render --cpu`).
    ProcessOnly,
}

/// One command of a suite, run once per build and repetition.
#[derive(Debug, Clone)]
pub struct Case {
    pub suite: Suite,
    /// `binary`, `teapot 1920x1080`, `motion simple 4x4`, ... (unique within the suite with
    /// `strategy`).
    pub name: String,
    /// The strategy the command names, for the row; `None` where the output names it
    /// (schedbench's records).
    pub strategy: Option<String>,
    pub program: Program,
    pub args: Vec<Arg>,
    pub reader: Reader,
    /// Every image of this case's rows must have one md5 (the strategies and builds render
    /// the same image).
    pub same_image: bool,
    /// The process's own wall time goes into the row's notes (parsing included).
    pub process_time: bool,
    /// Run by the build under test only, before the cases that read its output.
    pub reference: bool,
    /// The index (in the plan) of the reference case whose output this case reads.
    pub needs: Option<usize>,
}

/// What the plan is made from.
pub struct PlanInput<'a> {
    pub size: Size,
    /// `--runs`.
    pub runs: Option<u32>,
    /// `--scene`s.
    pub scenes: &'a [String],
    /// The shared scene folder.
    pub data: &'a Path,
    /// Where generated inputs (scenes, references) go: the scratch folder.
    pub scratch: &'a Path,
}

/// The cases of `suites` in order. Errors: a scene that cannot be found or generated, named.
pub fn plan(suites: &[Suite], input: &PlanInput) -> Result<Vec<Case>, Error> {
    let mut cases = Vec::new();
    for &suite in suites {
        let mut p = Planner {
            suite,
            input,
            cases: &mut cases,
        };
        match suite {
            Suite::Trees => p.trees(),
            Suite::Overflow => p.overflow(),
            Suite::Frames => p.frames()?,
            Suite::Bench => p.bench()?,
            Suite::Peer => p.peer()?,
            Suite::RasterModes => p.raster_modes()?,
            Suite::Effects => p.effects()?,
            Suite::ManyPatches => p.many_patches()?,
            Suite::Bfs => p.bfs(),
            Suite::Mandelbrot => p.mandelbrot(),
            Suite::Report => p.suite(),
            Suite::GpuTests => p.gpu_tests(),
        }
    }
    Ok(cases)
}

/// Keeps the cases whose name contains one of `only` (all without it), and the references
/// those read; `needs` indices are renumbered.
pub fn select(cases: Vec<Case>, only: &[String]) -> Vec<Case> {
    if only.is_empty() {
        return cases;
    }
    let mut keep: Vec<bool> = cases
        .iter()
        .map(|c| only.iter().any(|t| c.name.contains(t.as_str())))
        .collect();
    for (i, c) in cases.iter().enumerate() {
        if let Some(r) = c.needs.filter(|_| keep[i]) {
            keep[r] = true;
        }
    }
    let mut new_index = vec![None; cases.len()];
    let mut kept = Vec::new();
    for (i, mut c) in cases.into_iter().enumerate() {
        if keep[i] {
            c.needs = c.needs.and_then(|r| new_index[r]);
            new_index[i] = Some(kept.len());
            kept.push(c);
        }
    }
    kept
}

/// Strategies of the Reyes frames, in the order docs/results.md tables them.
const FRAME_STRATEGIES: [&str; 3] = ["megakernel", "multipass", "multipass-host"];
/// The tree presets, as `schedbench --preset` names them.
const TREE_PRESETS: [&str; 5] = ["binary", "irregular", "deep", "large-payload", "heavy-work"];
/// The overflow tree: 2,309,335 items from 45 roots (its queues grow ~16 times from 16 slots).
const OVERFLOW_TREE: [&str; 10] = [
    "--seed",
    "32",
    "--depth",
    "15",
    "--fanout",
    "uniform:4",
    "--roots",
    "45",
    "--workgroups",
    "485",
];
/// `--size small`'s trees: each preset's shape, cut to 8 roots and depth 8.
const SMALL_TREE: [&str; 4] = ["--roots", "8", "--depth", "8"];

struct Planner<'a, 'b> {
    suite: Suite,
    input: &'a PlanInput<'b>,
    cases: &'a mut Vec<Case>,
}

fn lits<S: AsRef<std::ffi::OsStr>>(args: impl IntoIterator<Item = S>) -> Vec<Arg> {
    args.into_iter()
        .map(|a| Arg::Lit(a.as_ref().to_os_string()))
        .collect()
}

impl Planner<'_, '_> {
    fn small(&self) -> bool {
        self.input.size == Size::Small
    }

    /// `--runs`, else `full` on full sizes and `small` on small ones.
    fn runs(&self, full: u32, small: u32) -> String {
        self.input
            .runs
            .unwrap_or(if self.small() { small } else { full })
            .to_string()
    }

    /// Adds a case; returns its index.
    fn add(
        &mut self,
        name: String,
        strategy: Option<&str>,
        program: Program,
        args: Vec<Arg>,
        reader: Reader,
    ) -> usize {
        self.cases.push(Case {
            suite: self.suite,
            name,
            strategy: strategy.map(str::to_string),
            program,
            args,
            reader,
            same_image: false,
            process_time: false,
            reference: false,
            needs: None,
        });
        self.cases.len() - 1
    }

    fn last(&mut self) -> &mut Case {
        self.cases.last_mut().expect("a case was added")
    }

    /// `schedbench ARGS --runs N --json`, strategies from the records.
    fn schedbench(&mut self, name: String, args: Vec<String>, runs: String) {
        let mut args = lits(args);
        args.extend(lits(["--runs", &runs, "--json"]));
        self.add(name, None, Program::Schedbench, args, Reader::Schedbench);
    }

    fn trees(&mut self) {
        let runs = self.runs(10, 2);
        for preset in TREE_PRESETS {
            let mut tree: Vec<String> = ["--workload", "tree", "--preset", preset]
                .map(String::from)
                .to_vec();
            if self.small() {
                tree.extend(SMALL_TREE.map(String::from));
            }
            let all = [&tree[..], &["--strategy".into(), "all".into()]].concat();
            self.schedbench(preset.into(), all, runs.clone());
            let fifo = [
                &tree[..],
                &["--strategy", "megakernel", "--policy", "fifo"].map(String::from),
            ]
            .concat();
            self.schedbench(preset.into(), fifo, runs.clone());
        }
    }

    fn overflow(&mut self) {
        let runs = self.runs(5, 2);
        let tree: Vec<String> = if self.small() {
            [
                "--seed",
                "32",
                "--depth",
                "8",
                "--fanout",
                "uniform:4",
                "--roots",
                "8",
            ]
            .map(String::from)
            .to_vec()
        } else {
            OVERFLOW_TREE.map(String::from).to_vec()
        };
        for (name, capacity) in [("room enough", None), ("capacity 16", Some("16"))] {
            let mut args: Vec<String> = ["--workload", "tree", "--strategy", "all"]
                .map(String::from)
                .to_vec();
            args.extend(tree.iter().cloned());
            if let Some(c) = capacity {
                args.extend(["--capacity".into(), c.into()]);
            }
            self.schedbench(name.into(), args, runs.clone());
        }
    }

    fn bfs(&mut self) {
        let scales: &[u32] = if self.small() { &[10] } else { &[20, 22] };
        self.sweep("bfs", "--scale", scales, |scale| format!("scale {scale}"));
    }

    fn mandelbrot(&mut self) {
        let sides: &[u32] = if self.small() { &[256] } else { &[1024, 4096] };
        self.sweep("mandelbrot", "--size-px", sides, |side| {
            format!("{side}x{side}")
        });
    }

    /// `schedbench --workload WORKLOAD --strategy all FLAG V` for each of `values`, 10 timed
    /// runs (2 small), each case named by `name`.
    fn sweep(&mut self, workload: &str, flag: &str, values: &[u32], name: impl Fn(u32) -> String) {
        let runs = self.runs(10, 2);
        for &v in values {
            let args = ["--workload", workload, "--strategy", "all", flag]
                .map(String::from)
                .into_iter()
                .chain([v.to_string()])
                .collect();
            self.schedbench(name(v), args, runs.clone());
        }
    }

    fn suite(&mut self) {
        let size = if self.small() { "small" } else { "full" };
        let mut args = lits(["--suite", "--size", size, "--runs", &self.runs(5, 2)]);
        args.extend([Arg::Lit("--out".into()), Arg::Out("")]);
        self.add(
            format!("{size} suite"),
            None,
            Program::Schedbench,
            args,
            Reader::SuiteReport,
        );
    }

    fn gpu_tests(&mut self) {
        for name in GPU_TESTS {
            self.add(
                name.into(),
                None,
                Program::Test(name),
                lits(["--test-threads", "1"]),
                Reader::Tests,
            );
            self.last().process_time = true;
        }
    }

    /// The `--scene`s, else `default`, as (name, argument).
    fn scenes(&self, default: &[&str]) -> Result<Vec<(String, OsString)>, Error> {
        let names: Vec<String> = if self.input.scenes.is_empty() {
            default.iter().map(|s| s.to_string()).collect()
        } else {
            self.input.scenes.to_vec()
        };
        names
            .into_iter()
            .map(|n| {
                let arg = scene_arg(&n, self.input.data)?;
                Ok((scene_label(&n), arg))
            })
            .collect()
    }

    /// `(width, height)` pairs: `full`, or 320x240 on small sizes.
    fn sizes(&self, full: &[(u32, u32)]) -> Vec<(u32, u32)> {
        if self.small() {
            vec![(320, 240)]
        } else {
            full.to_vec()
        }
    }

    /// `reyes render SCENE ARGS --runs N -o IMAGE --stats JSON`.
    fn render(&mut self, name: String, strategy: &str, scene: &OsString, args: Vec<Arg>) -> usize {
        let mut all = vec![Arg::Lit("render".into()), Arg::Lit(scene.clone())];
        all.extend(args);
        all.extend([
            Arg::Lit("-o".into()),
            Arg::Image,
            Arg::Lit("--stats".into()),
            Arg::Out(".json"),
        ]);
        self.add(name, Some(strategy), Program::Reyes, all, Reader::Render)
    }

    fn frames(&mut self) -> Result<(), Error> {
        let runs = self.runs(10, 2);
        for (scene, arg) in self.scenes(&["teapot", "killeroo"])? {
            for (w, h) in self.sizes(&[(1920, 1080)]) {
                for strategy in FRAME_STRATEGIES {
                    let args = lits([
                        "--width",
                        &w.to_string(),
                        "--height",
                        &h.to_string(),
                        "--strategy",
                        strategy,
                        "--runs",
                        &runs,
                    ]);
                    self.render(format!("{scene} {w}x{h}"), strategy, &arg, args);
                    self.last().same_image = true;
                }
            }
        }
        Ok(())
    }

    /// `reyes bench SCENE --width W --height H --strategy S --frames N ARGS --json`.
    fn bench_case(
        &mut self,
        name: String,
        strategy: &str,
        scene: &OsString,
        (w, h): (u32, u32),
        frames: &str,
        extra: &[&str],
    ) {
        let mut args = vec![Arg::Lit("bench".into()), Arg::Lit(scene.clone())];
        args.extend(lits([
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--strategy",
            strategy,
            "--frames",
            frames,
        ]));
        if self.small() {
            args.extend(lits(["--warmup", "2"]));
        }
        args.extend(lits(extra));
        args.push(Arg::Lit("--json".into()));
        let peer = extra.contains(&"--peer");
        self.add(
            name,
            Some(strategy),
            Program::Reyes,
            args,
            Reader::Bench { peer },
        );
    }

    fn bench(&mut self) -> Result<(), Error> {
        let frames = self.runs(200, 5);
        for (scene, arg) in self.scenes(&["teapot", "uteapot", "killeroo"])? {
            for size in self.sizes(&[(1920, 1080), (3840, 2160)]) {
                for strategy in ["megakernel", "multipass"] {
                    let name = format!("{scene} {}x{}", size.0, size.1);
                    self.bench_case(name, strategy, &arg, size, &frames, &["--turntable"]);
                }
            }
        }
        Ok(())
    }

    fn peer(&mut self) -> Result<(), Error> {
        let frames = self.runs(100, 5);
        for (scene, arg) in self.scenes(&["teapot", "uteapot", "killeroo"])? {
            for size in self.sizes(&[(1920, 1080), (3840, 2160)]) {
                for strategy in ["megakernel", "multipass"] {
                    let name = format!("{scene} {}x{}", size.0, size.1);
                    let extra = ["--turntable", "--peer", "raster"];
                    self.bench_case(name, strategy, &arg, size, &frames, &extra);
                }
            }
        }
        Ok(())
    }

    fn raster_modes(&mut self) -> Result<(), Error> {
        let frames = self.runs(100, 5);
        let size = self.sizes(&[(1920, 1080)])[0];
        for (scene, arg) in self.scenes(&["teapot", "killeroo"])? {
            for mp in ["1", "0.5"] {
                for mode in ["bbox", "nearest"] {
                    let name = format!("{scene} mp {mp} {mode}");
                    let extra = ["--mp-size", mp, "--raster", mode];
                    self.bench_case(name, "megakernel", &arg, size, &frames, &extra);
                }
            }
        }
        Ok(())
    }

    /// Sattler & Steinberger's comparison on Killeroo: per effect a bounding-box reference at
    /// 16x16 samples, then every sampling algorithm at 4x4, 5x5 and 8x8 against it; the still
    /// frame without effect flags; displacement (the model's `disp_textured` shaders, which
    /// the renderer lacks, replaced by its built-in `bumps`) with both normal modes.
    fn effects(&mut self) -> Result<(), Error> {
        let runs = self.runs(10, 2);
        let killeroo = scene_arg("killeroo", self.input.data)?;
        let (w, h) = if self.small() { (160, 120) } else { (800, 600) };
        let frame = lits([
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--strategy",
            "megakernel",
        ]);
        let (reference_samples, samples): (&str, &[&str]) = if self.small() {
            ("4", &["2"])
        } else {
            ("16", &["4", "5", "8"])
        };
        let algorithms: &[&str] = if self.small() {
            &["simple", "interleave:2", "bbox"]
        } else {
            &[
                "simple",
                "interleave:2",
                "interleave:3",
                "interleave:4",
                "bbox",
            ]
        };
        let effects = [
            ("motion", ["--spin", "30"]),
            ("dof", ["--dof", "2.8,50,454"]),
            ("still", ["--spin", "0"]),
        ];
        for (effect, flags) in effects {
            let exr = self.input.scratch.join(format!("reference-{effect}.exr"));
            let mut args = frame.clone();
            args.extend(lits(flags));
            args.extend(lits(["--sampling", "bbox", "--samples", reference_samples]));
            args.extend([Arg::Lit("--exr".into()), Arg::Lit(exr.clone().into())]);
            let name = format!("{effect} reference bbox {reference_samples}x{reference_samples}");
            let reference = self.render(name, "megakernel", &killeroo, args);
            self.last().reference = true;
            for s in samples {
                for a in algorithms {
                    let (algorithm, tile) = a.split_once(':').unwrap_or((a, ""));
                    let mut args = frame.clone();
                    args.extend(lits(flags));
                    args.extend(lits(["--sampling", algorithm]));
                    if !tile.is_empty() {
                        args.extend(lits(["--il-tile", tile]));
                    }
                    args.extend(lits(["--samples", s, "--runs", &runs, "--compare-to"]));
                    args.push(Arg::Lit(exr.clone().into()));
                    let name = format!("{effect} {a} {s}x{s}");
                    self.render(name, "megakernel", &killeroo, args);
                    self.last().needs = Some(reference);
                }
            }
        }
        for s in samples {
            let mut args = frame.clone();
            args.extend(lits(["--samples", s, "--runs", &runs]));
            self.render(format!("plain {s}x{s}"), "megakernel", &killeroo, args);
        }
        let bumps = self.input.scratch.join("killeroo-bumps.rib");
        write_bumps_killeroo(Path::new(&killeroo), &bumps)?;
        let (w, h) = self.sizes(&[(1920, 1080)])[0];
        for (name, scene, normals) in [
            ("displacement none", &killeroo, None),
            (
                "displacement exact normals",
                &bumps.clone().into(),
                Some("exact"),
            ),
            (
                "displacement approximate normals",
                &bumps.clone().into(),
                Some("approximate"),
            ),
        ] {
            let mut args = lits([
                "--width",
                &w.to_string(),
                "--height",
                &h.to_string(),
                "--strategy",
                "megakernel",
            ]);
            if let Some(n) = normals {
                args.extend(lits(["--displacement-normals", n]));
            }
            args.extend(lits(["--runs", &runs]));
            self.render(name.into(), "megakernel", scene, args);
        }
        Ok(())
    }

    /// Scenes of `nx * ny` tiny bilinear patches ([`write_many_patches`]) on every strategy
    /// (`reyes render --runs N`, the file's 640x480) and the CPU twin (`--cpu`): process time
    /// (parsing included) in the notes.
    fn many_patches(&mut self) -> Result<(), Error> {
        let runs = self.runs(3, 1);
        let grids: &[(u32, u32)] = if self.small() {
            &[(20, 20)]
        } else {
            &[(1000, 1000), (2000, 1000)]
        };
        for &(nx, ny) in grids {
            let file = self.input.scratch.join(format!("many-{nx}x{ny}.rib"));
            write_many_patches(&file, nx, ny).map_err(|source| Error::Write {
                path: file.clone(),
                source,
            })?;
            let scene: OsString = file.into();
            let name = format!("{} patches", nx * ny);
            for strategy in FRAME_STRATEGIES {
                let args = lits(["--strategy", strategy, "--runs", &runs]);
                self.render(name.clone(), strategy, &scene, args);
                self.last().process_time = true;
            }
            let args = vec![
                Arg::Lit("render".into()),
                Arg::Lit(scene.clone()),
                Arg::Lit("--cpu".into()),
                Arg::Lit("-o".into()),
                Arg::Image,
            ];
            self.add(name, Some("cpu"), Program::Reyes, args, Reader::ProcessOnly);
            self.last().process_time = true;
        }
        Ok(())
    }
}

/// A scene's name in the table: `teapot`, `killeroo`, a file's stem.
fn scene_label(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .map_or(name.to_string(), |s| s.to_string_lossy().into_owned())
}

/// The `reyes` argument for a scene: `teapot` as is (built in), else an existing file, a path
/// in the shared data, or `rib/NAME.rib` there. Errors name the places looked at.
pub fn scene_arg(name: &str, data: &Path) -> Result<OsString, Error> {
    if name == "teapot" {
        return Ok(name.into());
    }
    let candidates = [
        PathBuf::from(name),
        data.join(name),
        data.join("rib").join(format!("{name}.rib")),
    ];
    candidates
        .iter()
        .find(|p| p.is_file())
        .map(|p| p.clone().into_os_string())
        .ok_or_else(|| {
            let looked: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
            Error::SceneNotFound {
                name: name.to_string(),
                looked: looked.join(", "),
            }
        })
}

/// Writes Killeroo with its `disp_textured` displacement (a shader the renderer does not have)
/// replaced by the built-in `"bumps"` at frequency 4, keeping `Km`.
fn write_bumps_killeroo(killeroo: &Path, out: &Path) -> Result<(), Error> {
    let text = std::fs::read_to_string(killeroo).map_err(|source| Error::Read {
        path: killeroo.to_path_buf(),
        source,
    })?;
    const SHADER: &str = "Displacement \"disp_textured\"";
    if !text.contains(SHADER) {
        return Err(Error::NoShaderToReplace {
            path: killeroo.to_path_buf(),
            shader: SHADER,
        });
    }
    let bumps = text.replace(SHADER, "Displacement \"bumps\" \"frequency\" 4");
    std::fs::write(out, bumps).map_err(|source| Error::Write {
        path: out.to_path_buf(),
        source,
    })
}

/// Writes a 640x480 scene of `nx * ny` bilinear patches, each half a grid step wide, in a
/// 6-unit-wide grid facing the camera: the field's hostile many-patches scene, larger.
pub fn write_many_patches(out: &Path, nx: u32, ny: u32) -> std::io::Result<()> {
    use std::io::Write;
    let mut f = std::io::BufWriter::new(std::fs::File::create(out)?);
    f.write_all(
        b"Format 640 480 1\nProjection \"perspective\" \"fov\" 40\nTranslate 0 0 10\nWorldBegin\n\
          LightSource \"distantlight\" 1 \"from\" [0 0 -1] \"to\" [0 0 0]\n",
    )?;
    let step = 6.0 / nx as f64;
    let half = step * 0.5;
    for j in 0..ny {
        let y = (-3.0 * ny as f64) / nx as f64 + j as f64 * step;
        for i in 0..nx {
            let x = -3.0 + i as f64 * step;
            writeln!(
                f,
                "Patch \"bilinear\" \"P\" [{:.6} {:.6} 0 {:.6} {:.6} 0 {:.6} {:.6} 0 {:.6} {:.6} 0]",
                x,
                y,
                x + half,
                y,
                x,
                y + half,
                x + half,
                y + half
            )?;
        }
    }
    f.write_all(b"WorldEnd\n")?;
    f.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input<'a>(size: Size, data: &'a Path, scratch: &'a Path) -> PlanInput<'a> {
        PlanInput {
            size,
            runs: None,
            scenes: &[],
            data,
            scratch,
        }
    }

    #[test]
    fn trees_run_every_preset_under_every_strategy_and_the_fifo_policy() {
        let dir = tempfile::tempdir().unwrap();
        let cases = plan(&[Suite::Trees], &input(Size::Full, dir.path(), dir.path())).unwrap();
        assert_eq!(cases.len(), 10);
        let line = |c: &Case| -> Vec<String> {
            c.args
                .iter()
                .map(|a| match a {
                    Arg::Lit(s) => s.to_string_lossy().into_owned(),
                    other => format!("{other:?}"),
                })
                .collect()
        };
        assert_eq!(
            line(&cases[0]).join(" "),
            "--workload tree --preset binary --strategy all --runs 10 --json"
        );
        assert_eq!(
            line(&cases[9]).join(" "),
            "--workload tree --preset heavy-work --strategy megakernel --policy fifo --runs 10 --json"
        );
        let small = plan(&[Suite::Trees], &input(Size::Small, dir.path(), dir.path())).unwrap();
        assert!(
            line(&small[0])
                .join(" ")
                .contains("--roots 8 --depth 8 --strategy all --runs 2")
        );
    }

    #[test]
    fn a_missing_scene_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let e = plan(&[Suite::Frames], &input(Size::Full, dir.path(), dir.path()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("scene `killeroo` not found"), "{e}");
        assert!(e.contains("REYES_SHARED_DATA"), "{e}");
    }

    #[test]
    fn selecting_a_case_keeps_the_reference_it_compares_to() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("rib")).unwrap();
        std::fs::write(
            dir.path().join("rib/killeroo.rib"),
            "AttributeBegin\nDisplacement \"disp_textured\" \"Km\" 1\nAttributeEnd\n",
        )
        .unwrap();
        let cases = plan(
            &[Suite::Effects],
            &input(Size::Small, dir.path(), dir.path()),
        )
        .unwrap();
        let kept = select(cases, &["dof bbox".into()]);
        let names: Vec<&str> = kept.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["dof reference bbox 4x4", "dof bbox 2x2"]);
        assert_eq!(kept[1].needs, Some(0));
        assert!(kept[0].reference);
        let bumps = std::fs::read_to_string(dir.path().join("killeroo-bumps.rib")).unwrap();
        assert!(bumps.contains("Displacement \"bumps\" \"frequency\" 4 \"Km\" 1"));
    }

    /// The same text as the Python generator the figures of docs/results.md were measured with
    /// (`'%.6f'` of the same double arithmetic).
    #[test]
    fn many_patches_scene_is_a_grid_of_bilinear_patches() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("m.rib");
        write_many_patches(&f, 4, 2).unwrap();
        let text = std::fs::read_to_string(&f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 5 + 8 + 1);
        assert_eq!(
            lines[5],
            "Patch \"bilinear\" \"P\" [-3.000000 -1.500000 0 -2.250000 -1.500000 0 -3.000000 -0.750000 0 -2.250000 -0.750000 0]"
        );
        assert_eq!(lines[13], "WorldEnd");
    }
}
