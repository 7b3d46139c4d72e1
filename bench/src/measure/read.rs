//! Reading what a process wrote (`schedbench --json` records, the suite's `runs.jsonl`,
//! `reyes render --stats`, `reyes bench --json`, the test harness's summary) into
//! [`Sample`]s: the timed values of one strategy with what was checked. Only the keys the
//! table needs are read; the rest stays in the files.

use super::error::Error;
use super::md5::md5_hex;
use super::plan::{Case, Reader};
use super::run::Process;
use serde::Deserialize;
use std::path::Path;

/// Whether a row's results were checked, and how that came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Check {
    /// Checked and right (schedbench: every run equals the CPU reference; frames: one image;
    /// tests: all passed).
    Yes,
    /// Checked and wrong, or the process failed.
    No,
    /// Nothing to check (timings of images that differ by design).
    NotChecked,
}

impl Check {
    /// Both checks: `No` wins, then `Yes`.
    pub fn and(self, o: Check) -> Check {
        match (self, o) {
            (Check::No, _) | (_, Check::No) => Check::No,
            (Check::Yes, _) | (_, Check::Yes) => Check::Yes,
            _ => Check::NotChecked,
        }
    }

    /// `yes`, `no`, `-`.
    pub fn label(self) -> &'static str {
        match self {
            Check::Yes => "yes",
            Check::No => "no",
            Check::NotChecked => "-",
        }
    }
}

/// The timed values of one strategy in one process, ms.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// The case's name when the output names it (the suite's workload and size).
    pub case: Option<String>,
    pub strategy: String,
    pub adapter: Option<String>,
    /// GPU time per timed run (empty without timestamp queries, and for CPU runs).
    pub gpu_ms: Vec<f64>,
    /// Wall time per timed run.
    pub wall_ms: Vec<f64>,
    pub check: Check,
    /// What else the output says (fps, image error, test counts, the first error).
    pub notes: Vec<String>,
    /// The image's md5.
    pub md5: Option<String>,
}

impl Sample {
    fn new(strategy: &str) -> Sample {
        Sample {
            case: None,
            strategy: strategy.to_string(),
            adapter: None,
            gpu_ms: Vec::new(),
            wall_ms: Vec::new(),
            check: Check::NotChecked,
            notes: Vec::new(),
            md5: None,
        }
    }

    /// A process that did not give results: checked, wrong, with the reason.
    fn failed(strategy: &str, why: String) -> Sample {
        Sample {
            check: Check::No,
            notes: vec![why],
            ..Sample::new(strategy)
        }
    }
}

/// A line of `schedbench --json` and of the suite's `runs.jsonl` (the bench crate's
/// `RunRecord`), the keys the table reads.
#[derive(Debug, Deserialize)]
struct SchedRecord {
    workload: String,
    strategy: String,
    size: String,
    adapter: String,
    verified: bool,
    #[serde(default)]
    error: Option<String>,
    gpu_ms: Option<f64>,
    wall_ms: Option<f64>,
}

/// `reyes render --stats`, the keys the table reads.
#[derive(Debug, Deserialize)]
struct RenderStats {
    adapter: String,
    #[serde(default)]
    runs: Option<RunTimes>,
    #[serde(default)]
    image_error: Option<ImageError>,
}

#[derive(Debug, Deserialize)]
struct RunTimes {
    gpu_ms: Option<AllTimes>,
    wall_ms: Option<AllTimes>,
}

#[derive(Debug, Deserialize)]
struct AllTimes {
    all: Vec<f64>,
}

#[derive(Debug, Deserialize)]
struct ImageError {
    /// Null when the images are identical (infinite PSNR).
    psnr_db: Option<f64>,
    flip_mean: f64,
}

/// `reyes bench --json`, the keys the table reads.
#[derive(Debug, Deserialize)]
struct BenchReport {
    adapter: String,
    pipelined: bool,
    not_pipelined: Option<String>,
    wall_ms: P95,
    gpu_ms: Option<P95>,
    fps: f64,
    rerendered: u32,
    per_frame: Vec<FrameTimes>,
    #[serde(default)]
    peer: Option<PeerReport>,
}

#[derive(Debug, Deserialize)]
struct P95 {
    p95: f64,
}

#[derive(Debug, Deserialize)]
struct FrameTimes {
    wall_ms: f64,
    gpu_ms: Option<f64>,
}

#[derive(Debug, Deserialize)]
struct PeerReport {
    peer: String,
    msaa_samples: u32,
    msaa_wanted: u32,
    fps: f64,
    triangles: Median,
    redrawn: u32,
    difference: Vec<PeerDifference>,
    per_frame: Vec<FrameTimes>,
}

#[derive(Debug, Deserialize)]
struct Median {
    median: f64,
}

#[derive(Debug, Deserialize)]
struct PeerDifference {
    psnr_db: Option<f64>,
    over: f64,
}

/// The samples of `process`, a run of `case`. A process that failed gives one failed sample
/// (schedbench's exit status 1, some run not verified, still gives its records).
pub fn read(case: &Case, process: &Process) -> Vec<Sample> {
    let strategy = case.strategy.as_deref().unwrap_or("-");
    let failure = process.failure();
    let mut samples = match case.reader {
        Reader::Schedbench => {
            let text = std::fs::read_to_string(&process.stdout).unwrap_or_default();
            schedbench_samples(&text, false)
        }
        Reader::SuiteReport => {
            let text = std::fs::read_to_string(process.stem.join("runs.jsonl")).unwrap_or_default();
            schedbench_samples(&text, true)
        }
        _ if failure.is_some() => Vec::new(),
        Reader::Render => {
            let mut json = process.stem.clone().into_os_string();
            json.push(".json");
            match render_sample(strategy, Path::new(&json)) {
                Ok(s) => vec![s],
                Err(e) => vec![Sample::failed(strategy, e.to_string())],
            }
        }
        Reader::Bench { peer } => {
            let text = std::fs::read_to_string(&process.stdout).unwrap_or_default();
            bench_samples(strategy, &text, peer)
                .unwrap_or_else(|e| vec![Sample::failed(strategy, e.to_string())])
        }
        Reader::Tests => {
            let text = std::fs::read_to_string(&process.stdout).unwrap_or_default();
            vec![test_sample(&text)]
        }
        Reader::ProcessOnly => vec![Sample::new(strategy)],
    };
    if let Some(why) = failure {
        // schedbench exits 1 when some run was not verified; its records say which.
        let unverified_only = matches!(case.reader, Reader::Schedbench | Reader::SuiteReport)
            && process.code() == Some(1)
            && !samples.is_empty();
        if !unverified_only {
            match samples.first_mut() {
                Some(s) => {
                    s.check = Check::No;
                    s.notes.push(why);
                }
                None => samples.push(Sample::failed(strategy, why)),
            }
        }
    }
    if let Some(image) = &process.image
        && let Ok(bytes) = std::fs::read(image)
    {
        for s in &mut samples {
            s.md5 = Some(md5_hex(&bytes));
        }
    }
    if case.process_time {
        for s in &mut samples {
            s.notes.push(format!("process {:.1} s", process.seconds));
        }
    }
    samples
}

/// One sample per (workload and size when `by_case`,) strategy, in the order first seen.
fn schedbench_samples(text: &str, by_case: bool) -> Vec<Sample> {
    let mut samples: Vec<Sample> = Vec::new();
    for line in text.lines().filter(|l| l.starts_with('{')) {
        let r: SchedRecord = match serde_json::from_str(line) {
            Ok(r) => r,
            Err(e) => {
                samples.push(Sample::failed("-", format!("unreadable record: {e}")));
                continue;
            }
        };
        let case = by_case.then(|| format!("{} {}", r.workload, r.size));
        let i = match samples
            .iter()
            .position(|s| s.strategy == r.strategy && s.case == case)
        {
            Some(i) => i,
            None => {
                samples.push(Sample {
                    case,
                    adapter: Some(r.adapter.clone()),
                    check: Check::Yes,
                    ..Sample::new(&r.strategy)
                });
                samples.len() - 1
            }
        };
        let s = &mut samples[i];
        s.gpu_ms.extend(r.gpu_ms);
        s.wall_ms.extend(r.wall_ms);
        if !r.verified {
            if s.check != Check::No {
                s.notes
                    .push(r.error.unwrap_or_else(|| "not verified".into()));
            }
            s.check = Check::No;
        }
    }
    samples
}

fn render_sample(strategy: &str, json: &Path) -> Result<Sample, Error> {
    let text = std::fs::read_to_string(json).map_err(|source| Error::Read {
        path: json.to_path_buf(),
        source,
    })?;
    let stats: RenderStats = serde_json::from_str(&text).map_err(|source| Error::ParseJson {
        path: json.to_path_buf(),
        source,
    })?;
    let mut s = Sample {
        adapter: Some(stats.adapter),
        ..Sample::new(strategy)
    };
    if let Some(runs) = stats.runs {
        s.gpu_ms = runs.gpu_ms.map_or(Vec::new(), |t| t.all);
        s.wall_ms = runs.wall_ms.map_or(Vec::new(), |t| t.all);
    }
    if let Some(e) = stats.image_error {
        let psnr = e.psnr_db.map_or("inf".into(), |p| format!("{p:.2}"));
        s.notes
            .push(format!("PSNR {psnr} dB, FLIP {:.4}", e.flip_mean));
    }
    Ok(s)
}

fn bench_samples(strategy: &str, text: &str, with_peer: bool) -> Result<Vec<Sample>, Error> {
    let r: BenchReport = serde_json::from_str(text).map_err(Error::ParseBenchJson)?;
    let mut reyes = Sample {
        adapter: Some(r.adapter.clone()),
        gpu_ms: r.per_frame.iter().filter_map(|f| f.gpu_ms).collect(),
        wall_ms: r.per_frame.iter().map(|f| f.wall_ms).collect(),
        ..Sample::new(strategy)
    };
    let gpu_p95 = r.gpu_ms.map_or("n/a".into(), |g| format!("{:.3}", g.p95));
    reyes.notes.push(format!(
        "{} fps, p95 wall {:.3} GPU {gpu_p95}",
        fps(r.fps),
        r.wall_ms.p95
    ));
    if r.rerendered > 0 {
        reyes.notes.push(format!("{} re-rendered", r.rerendered));
    }
    if !r.pipelined {
        let why = r.not_pipelined.unwrap_or_default();
        reyes.notes.push(format!("not pipelined: {why}"));
    }
    let mut samples = vec![reyes];
    match (with_peer, r.peer) {
        (true, Some(p)) => {
            let mut peer = Sample {
                adapter: Some(r.adapter),
                gpu_ms: p.per_frame.iter().filter_map(|f| f.gpu_ms).collect(),
                wall_ms: p.per_frame.iter().map(|f| f.wall_ms).collect(),
                ..Sample::new(&format!("{} peer", p.peer))
            };
            peer.notes.push(format!(
                "{} fps, MSAA {}/{}, {:.2} M triangles",
                fps(p.fps),
                p.msaa_samples,
                p.msaa_wanted,
                p.triangles.median / 1e6
            ));
            for d in &p.difference {
                let psnr = d.psnr_db.map_or("inf".into(), |x| format!("{x:.1}"));
                peer.notes.push(format!(
                    "vs Reyes {psnr} dB, {:.2}% of pixels over",
                    d.over * 100.0
                ));
            }
            if p.redrawn > 0 {
                peer.notes.push(format!("{} redrawn", p.redrawn));
            }
            samples.push(peer);
        }
        (true, None) => samples.push(Sample::failed(
            "raster peer",
            "no peer in the report".into(),
        )),
        _ => {}
    }
    Ok(samples)
}

/// Frames per second: whole above 100, else to 0.1 (lavapipe's 0.4 fps stays readable).
fn fps(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.1}")
    }
}

/// The sums of the harness's `test result: ok. P passed; F failed; ...` lines.
fn test_sample(text: &str) -> Sample {
    let mut s = Sample::new("-");
    let (mut passed, mut failed, mut found) = (0u32, 0u32, false);
    for line in text.lines().filter(|l| l.starts_with("test result:")) {
        found = true;
        for part in line.split([';', '.']) {
            let mut words = part.split_whitespace();
            if let (Some(n), Some(what)) = (words.next(), words.next()) {
                match (n.parse::<u32>(), what) {
                    (Ok(n), "passed") => passed += n,
                    (Ok(n), "failed") => failed += n,
                    _ => {}
                }
            }
        }
    }
    s.check = if found && failed == 0 {
        Check::Yes
    } else {
        Check::No
    };
    s.notes.push(if found {
        format!("{passed} passed, {failed} failed")
    } else {
        "no test result line".into()
    });
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedbench_records_group_by_strategy_with_the_first_error() {
        let line = |strategy: &str, verified: bool, gpu: &str| {
            format!(
                r#"{{"workload":"tree","strategy":"{strategy}","size":"roots=8","adapter":"A","verified":{verified},"error":{},"gpu_ms":{gpu},"wall_ms":2.0,"items":5}}"#,
                if verified { "null" } else { "\"differs\"" }
            )
        };
        let text = [
            line("megakernel", true, "1.0"),
            "progress line".into(),
            line("cpu", true, "null"),
            line("megakernel", false, "3.0"),
        ]
        .join("\n");
        let s = schedbench_samples(&text, false);
        assert_eq!(s.len(), 2);
        assert_eq!(
            (s[0].strategy.as_str(), &s[0].gpu_ms[..], s[0].check),
            ("megakernel", &[1.0, 3.0][..], Check::No)
        );
        assert_eq!(s[0].notes, ["differs"]);
        assert_eq!(
            (s[1].gpu_ms.len(), s[1].wall_ms.len(), s[1].check),
            (0, 1, Check::Yes)
        );
        let by_case = schedbench_samples(&text, true);
        assert_eq!(by_case[0].case.as_deref(), Some("tree roots=8"));
    }

    #[test]
    fn test_counts_add_up_over_the_harness_lines() {
        let text = "running 3 tests\ntest a ... ok\n\
            test result: ok. 3 passed; 0 failed; 1 ignored; 0 measured; 0 filtered out; finished in 2.1s\n\
            test result: FAILED. 1 passed; 2 failed; 0 ignored; 0 measured; 0 filtered out\n";
        let s = test_sample(text);
        assert_eq!(
            (s.check, s.notes[0].as_str()),
            (Check::No, "4 passed, 2 failed")
        );
        assert_eq!(test_sample("").check, Check::No);
    }

    #[test]
    fn checks_combine_with_no_first() {
        assert_eq!(Check::Yes.and(Check::NotChecked), Check::Yes);
        assert_eq!(Check::NotChecked.and(Check::No), Check::No);
        assert_eq!(Check::NotChecked.and(Check::NotChecked), Check::NotChecked);
    }
}
