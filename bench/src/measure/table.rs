//! The table `measure` prints: one row per suite, case, strategy and build, pooling the timed
//! runs of that build's processes; median ± MAD from the scheduler's statistics
//! (`scheduler::stats::median_and_mad`, the spread measure of every figure in
//! docs/results.md), and with `--compare` the ratio of the build under test to the baseline
//! from the same invocation.

use super::cli::Suite;
use super::plan::Case;
use super::read::{Check, Sample};
use super::run::Build;
use scheduler::stats::median_and_mad;

/// The pooled results of one suite, case, strategy and build.
#[derive(Debug, Clone)]
pub struct Row {
    pub suite: Suite,
    pub case: String,
    pub strategy: String,
    pub build: Build,
    /// Every timed GPU time of every process, ms.
    pub gpu_ms: Vec<f64>,
    /// Every timed wall time, ms.
    pub wall_ms: Vec<f64>,
    /// Each process's median (GPU time, else wall time), ms, in the order run.
    pub per_process: Vec<f64>,
    /// Timed runs of each process.
    pub runs: Vec<usize>,
    pub check: Check,
    /// Distinct notes in the order first seen.
    pub notes: Vec<String>,
    /// Each process's image md5.
    pub md5: Vec<String>,
    /// Every image of this row's case must have one md5.
    same_image: bool,
    /// Position of the row's (suite, case, strategy) among the rows first seen: the display
    /// order, builds side by side.
    order: usize,
}

impl Row {
    /// GPU median and MAD, when the runs were GPU-timed.
    pub fn gpu(&self) -> Option<(f64, f64)> {
        (!self.gpu_ms.is_empty()).then(|| median_and_mad(&self.gpu_ms))
    }

    /// Wall median.
    pub fn wall(&self) -> Option<f64> {
        (!self.wall_ms.is_empty()).then(|| median_and_mad(&self.wall_ms).0)
    }

    /// The time ratios compare: the GPU median, else the wall median.
    fn time(&self) -> Option<f64> {
        self.gpu().map(|g| g.0).or(self.wall())
    }

    fn same_key(&self, o: &Row) -> bool {
        (self.suite, &self.case, &self.strategy) == (o.suite, &o.case, &o.strategy)
    }
}

/// Every row of an invocation.
#[derive(Debug, Default)]
pub struct Table {
    pub rows: Vec<Row>,
    /// Distinct adapter names in the outputs.
    pub adapters: Vec<String>,
    /// A ratio column (`--compare`).
    pub compare: bool,
}

impl Table {
    /// Adds a process's samples of `case`, run by `build`.
    pub fn add(&mut self, case: &Case, build: Build, samples: Vec<Sample>) {
        for s in samples {
            if let Some(a) = s.adapter.filter(|a| !self.adapters.contains(a)) {
                self.adapters.push(a);
            }
            let name = s.case.unwrap_or_else(|| case.name.clone());
            let key = |r: &Row| {
                (r.suite, r.case.as_str(), r.strategy.as_str())
                    == (case.suite, name.as_str(), s.strategy.as_str())
            };
            let order = match self.rows.iter().find(|r| key(r)) {
                Some(r) => r.order,
                None => self.rows.iter().map(|r| r.order + 1).max().unwrap_or(0),
            };
            let i = match self.rows.iter().position(|r| key(r) && r.build == build) {
                Some(i) => i,
                None => {
                    self.rows.push(Row {
                        suite: case.suite,
                        case: name.clone(),
                        strategy: s.strategy.clone(),
                        build,
                        gpu_ms: Vec::new(),
                        wall_ms: Vec::new(),
                        per_process: Vec::new(),
                        runs: Vec::new(),
                        check: Check::NotChecked,
                        notes: Vec::new(),
                        md5: Vec::new(),
                        same_image: case.same_image,
                        order,
                    });
                    self.rows.len() - 1
                }
            };
            let row = &mut self.rows[i];
            let timed = if s.gpu_ms.is_empty() {
                &s.wall_ms
            } else {
                &s.gpu_ms
            };
            if !timed.is_empty() {
                row.per_process.push(median_and_mad(timed).0);
            }
            row.runs.push(s.gpu_ms.len().max(s.wall_ms.len()));
            row.gpu_ms.extend(&s.gpu_ms);
            row.wall_ms.extend(&s.wall_ms);
            row.check = if row.runs.len() == 1 {
                s.check
            } else {
                row.check.and(s.check)
            };
            for n in s.notes {
                if !row.notes.contains(&n) {
                    row.notes.push(n);
                }
            }
            row.md5.extend(s.md5);
        }
    }

    /// Orders the rows (each case's strategies together, the baseline before the build under
    /// test) and checks the images of cases that must render one image: every md5 equal to
    /// the first row's first.
    pub fn finish(&mut self) {
        self.rows.sort_by_key(|r| (r.order, r.build));
        for i in 0..self.rows.len() {
            if !self.rows[i].same_image {
                continue;
            }
            let (suite, case) = (self.rows[i].suite, &self.rows[i].case);
            let first = self
                .rows
                .iter()
                .find(|r| r.same_image && r.suite == suite && &r.case == case)
                .and_then(|r| r.md5.first().cloned());
            let r = &mut self.rows[i];
            let same = first.is_some_and(|m| !r.md5.is_empty() && r.md5.iter().all(|x| *x == m));
            r.check = r.check.and(if same { Check::Yes } else { Check::No });
        }
    }

    /// Every row verified or not checked.
    pub fn all_good(&self) -> bool {
        self.rows.iter().all(|r| r.check != Check::No)
    }

    /// The ratio of `row` (the build under test) to its baseline row.
    fn ratio(&self, row: &Row) -> Option<f64> {
        if row.build != Build::New {
            return None;
        }
        let base = self
            .rows
            .iter()
            .find(|b| b.build == Build::Base && b.same_key(row))?;
        Some(row.time()? / base.time()?)
    }

    fn header(&self) -> Vec<&'static str> {
        let mut h = vec!["suite", "case", "strategy"];
        if self.compare {
            h.push("build");
        }
        h.extend([
            "GPU ms (median ± MAD)",
            "wall ms (median)",
            "runs",
            "verified",
        ]);
        if self.compare {
            h.push("new / base");
        }
        h.push("notes");
        h
    }

    fn cells(&self, r: &Row) -> Vec<String> {
        let mut c = vec![r.suite.name(), r.case.clone(), r.strategy.clone()];
        if self.compare {
            c.push(r.build.name().into());
        }
        c.push(
            r.gpu()
                .map_or("n/a".into(), |(m, d)| format!("{m:.3} ± {d:.3}")),
        );
        c.push(r.wall().map_or("n/a".into(), |w| format!("{w:.3}")));
        c.push(runs_label(&r.runs));
        c.push(r.check.label().into());
        if self.compare {
            c.push(self.ratio(r).map_or(String::new(), |x| format!("{x:.3}")));
        }
        let mut notes = r.notes.clone();
        let mut md5: Vec<&str> = r.md5.iter().map(|m| &m[..m.len().min(8)]).collect();
        md5.dedup();
        if !md5.is_empty() {
            notes.insert(0, format!("md5 {}", md5.join(", ")));
        }
        if r.per_process.len() > 1 {
            let each: Vec<String> = r.per_process.iter().map(|x| format!("{x:.3}")).collect();
            notes.push(format!("per process {}", each.join(", ")));
        }
        c.push(notes.join("; "));
        c
    }

    /// Lines above the table: adapters and builds.
    fn preamble(&self, builds: &[(Build, String)]) -> Vec<String> {
        let mut lines = vec![format!(
            "adapter: {}",
            if self.adapters.is_empty() {
                "(none reported)".to_string()
            } else {
                self.adapters.join("; ")
            }
        )];
        for (b, dir) in builds {
            lines.push(format!("{} build: {dir}", b.name()));
        }
        lines
    }

    /// Aligned columns (numbers right-aligned).
    pub fn text(&self, builds: &[(Build, String)]) -> String {
        let header = self.header();
        let rows: Vec<Vec<String>> = self.rows.iter().map(|r| self.cells(r)).collect();
        let mut width: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
        for r in &rows {
            for (w, c) in width.iter_mut().zip(r) {
                *w = (*w).max(c.chars().count());
            }
        }
        let numeric = |h: &str| h.contains("ms") || h == "runs" || h == "new / base";
        let line = |cells: &[String]| {
            let parts: Vec<String> = cells
                .iter()
                .zip(&header)
                .zip(&width)
                .enumerate()
                .map(|(i, ((c, h), w))| {
                    let pad = w.saturating_sub(c.chars().count());
                    if i + 1 == cells.len() {
                        c.clone()
                    } else if numeric(h) {
                        format!("{}{c}", " ".repeat(pad))
                    } else {
                        format!("{c}{}", " ".repeat(pad))
                    }
                })
                .collect();
            parts.join("  ").trim_end().to_string()
        };
        let mut out = self.preamble(builds);
        out.push(line(
            &header.iter().map(|h| h.to_string()).collect::<Vec<_>>(),
        ));
        out.extend(rows.iter().map(|r| line(r)));
        out.join("\n") + "\n"
    }

    /// A Markdown table, as docs/results.md has them.
    pub fn markdown(&self, builds: &[(Build, String)]) -> String {
        let header = self.header();
        let mut out: Vec<String> = self
            .preamble(builds)
            .into_iter()
            .map(|l| l + "  ")
            .collect();
        out.push(String::new());
        out.push(format!("| {} |", header.join(" | ")));
        let align: Vec<&str> = header
            .iter()
            .map(|h| {
                if h.contains("ms") || *h == "runs" || *h == "new / base" {
                    "---:"
                } else {
                    "---"
                }
            })
            .collect();
        out.push(format!("| {} |", align.join(" | ")));
        for r in &self.rows {
            let cells: Vec<String> = self
                .cells(r)
                .iter()
                .map(|c| c.replace('|', "\\|"))
                .collect();
            out.push(format!("| {} |", cells.join(" | ")));
        }
        out.join("\n") + "\n"
    }
}

/// `10`, or `2x10` for two processes of 10 runs, or the total when they differ; `-` for
/// processes that time nothing themselves (`reyes render --cpu`).
fn runs_label(runs: &[usize]) -> String {
    match runs {
        _ if runs.iter().all(|&n| n == 0) => "-".into(),
        [n] => n.to_string(),
        [n, rest @ ..] if rest.iter().all(|m| m == n) => format!("{}x{n}", runs.len()),
        _ => runs.iter().sum::<usize>().to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::plan::{Program, Reader};

    fn case(name: &str, same_image: bool) -> Case {
        Case {
            suite: Suite::Frames,
            name: name.into(),
            strategy: None,
            program: Program::Reyes,
            args: Vec::new(),
            reader: Reader::Render,
            same_image,
            process_time: false,
            reference: false,
            needs: None,
        }
    }

    fn sample(strategy: &str, gpu: &[f64], md5: &str) -> Sample {
        Sample {
            case: None,
            strategy: strategy.into(),
            adapter: Some("llvmpipe".into()),
            gpu_ms: gpu.to_vec(),
            wall_ms: gpu.iter().map(|g| g * 10.0).collect(),
            check: Check::NotChecked,
            notes: Vec::new(),
            md5: Some(md5.into()),
        }
    }

    #[test]
    fn builds_pool_their_processes_and_compare_by_gpu_median() {
        let c = case("teapot 320x240", true);
        let mut t = Table {
            compare: true,
            ..Table::default()
        };
        for _ in 0..2 {
            t.add(
                &c,
                Build::Base,
                vec![sample("megakernel", &[1.0, 1.0, 2.0], "aa")],
            );
            t.add(
                &c,
                Build::New,
                vec![sample("megakernel", &[1.5, 1.5, 9.0], "aa")],
            );
            t.add(&c, Build::Base, vec![sample("multipass", &[4.0], "aa")]);
            t.add(&c, Build::New, vec![sample("multipass", &[4.0], "bb")]);
        }
        t.finish();
        let order: Vec<(&str, Build)> = t
            .rows
            .iter()
            .map(|r| (r.strategy.as_str(), r.build))
            .collect();
        assert_eq!(
            order,
            [
                ("megakernel", Build::Base),
                ("megakernel", Build::New),
                ("multipass", Build::Base),
                ("multipass", Build::New)
            ]
        );
        assert_eq!(t.rows[1].gpu(), Some((1.5, 0.0)));
        assert_eq!(t.ratio(&t.rows[1]), Some(1.5));
        assert_eq!(runs_label(&t.rows[1].runs), "2x3");
        let checks: Vec<Check> = t.rows.iter().map(|r| r.check).collect();
        assert_eq!(checks, [Check::Yes, Check::Yes, Check::Yes, Check::No]);
        assert!(!t.all_good());
        let text = t.text(&[(Build::New, "target/release".into())]);
        assert!(text.starts_with("adapter: llvmpipe\nnew build: target/release\nsuite"));
        assert!(text.contains("1.500 ± 0.000"), "{text}");
        assert!(text.contains("per process 1.500, 1.500"), "{text}");
        let md = t.markdown(&[]);
        assert!(
            md.contains("| frames | teapot 320x240 | megakernel | new | 1.500 ± 0.000 |"),
            "{md}"
        );
    }

    #[test]
    fn rows_without_gpu_time_show_wall_time_and_no_check() {
        let mut t = Table::default();
        let mut s = sample("cpu", &[], "");
        s.wall_ms = vec![3.0, 5.0];
        s.md5 = None;
        t.add(&case("tree", false), Build::New, vec![s]);
        t.finish();
        let cells = t.cells(&t.rows[0]);
        assert_eq!(cells[3..6], ["n/a", "4.000", "2"]);
        assert_eq!(cells[6], "-");
        assert!(t.all_good());
    }
}
