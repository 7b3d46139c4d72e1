//! The workloads `schedbench` knows, by command-line name, and which of them the suite runs.

use crate::error::Error;
use crate::reyes_frames::{ReyesWorkload, SuiteScene};
use crate::scale::Scale;
use crate::strategy::GpuConfig;
use crate::tree::preset_workload;
use crate::workload::Workload;
use workloads::tree::TreePreset::*;

/// `--workload` names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WorkloadName {
    /// The synthetic split tree (`workloads::tree`); the suite runs every preset.
    Tree,
    /// Reyes frames: the built-in teapot and Killeroo (`reyes::gpu_render`).
    Reyes,
    /// Escape-time Mandelbrot with per-tile refinement (`workloads::mandelbrot`).
    Mandelbrot,
    /// Breadth-first search (`workloads::bfs`), with a frontier baseline.
    Bfs,
}

impl WorkloadName {
    pub const ALL: [WorkloadName; 4] = [
        WorkloadName::Tree,
        WorkloadName::Reyes,
        WorkloadName::Mandelbrot,
        WorkloadName::Bfs,
    ];

    pub fn name(self) -> &'static str {
        match self {
            WorkloadName::Tree => "tree",
            WorkloadName::Reyes => "reyes",
            WorkloadName::Mandelbrot => "mandelbrot",
            WorkloadName::Bfs => "bfs",
        }
    }

    /// The names of the workload's procedures (what `--procedure-steps` may name).
    pub fn procedures(self) -> &'static [&'static str] {
        match self {
            WorkloadName::Tree => &workloads::tree::PROCEDURES,
            WorkloadName::Reyes => &reyes::gpu_render::PROCEDURES,
            WorkloadName::Mandelbrot => &workloads::mandelbrot::PROCEDURES,
            WorkloadName::Bfs => &workloads::bfs::PROCEDURES,
        }
    }

    /// Whether this branch has the workload's code (every workload does now; the suite's
    /// summary still lists any that would not).
    pub fn built(self) -> bool {
        true
    }

    /// The suite's workloads of this kind at `scale`; an error when their input cannot be read
    /// (Killeroo's file) or generated (an R-MAT graph).
    pub fn suite(self, scale: Scale, config: &GpuConfig) -> Result<Vec<Box<dyn Workload>>, Error> {
        let c = config.clone();
        match self {
            WorkloadName::Tree => {
                // Presets of one program side by side, sharing its compiled schedulers.
                let order = [Binary, HeavyWork, Deep, Irregular, LargePayload];
                let first = preset_workload(order[0], scale, c.clone());
                let mut v: Vec<Box<dyn Workload>> = Vec::new();
                for &p in &order[1..] {
                    v.push(Box::new(
                        preset_workload(p, scale, c.clone()).sharing(&first),
                    ));
                }
                v.insert(0, Box::new(first));
                Ok(v)
            }
            WorkloadName::Reyes => {
                let teapot = ReyesWorkload::suite(SuiteScene::Teapot, scale, c.clone())?;
                let killeroo =
                    ReyesWorkload::suite(SuiteScene::Killeroo, scale, c.clone())?.sharing(&teapot);
                Ok(vec![Box::new(teapot), Box::new(killeroo)])
            }
            WorkloadName::Mandelbrot => {
                Ok(vec![Box::new(crate::mandelbrot::suite_workload(scale, c))])
            }
            WorkloadName::Bfs => Ok(vec![Box::new(crate::bfs::suite_workload(scale, c)?)]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use workloads::tree::TreePreset;

    #[test]
    fn the_suite_runs_every_tree_preset_once() {
        let mut names: Vec<String> = WorkloadName::Tree
            .suite(Scale::Small, &GpuConfig::default())
            .unwrap()
            .iter()
            .map(|w| w.name())
            .collect();
        names.sort();
        let mut want: Vec<String> = TreePreset::ALL
            .iter()
            .map(|p| format!("tree-{}", p.name()))
            .collect();
        want.sort();
        assert_eq!(names, want);
    }

    #[test]
    fn every_workload_is_in_the_suite_with_two_small_sizes() {
        for w in WorkloadName::ALL {
            assert!(w.built(), "{}", w.name());
        }
        for (w, name) in [
            (WorkloadName::Mandelbrot, "mandelbrot"),
            (WorkloadName::Bfs, "bfs"),
        ] {
            let suite = w.suite(Scale::Small, &GpuConfig::default()).unwrap();
            assert_eq!(suite.len(), 1);
            assert_eq!(suite[0].name(), name);
            assert_eq!(suite[0].sizes().len(), 2, "{name}");
        }
        let bfs = WorkloadName::Bfs
            .suite(Scale::Small, &GpuConfig::default())
            .unwrap();
        let strategies: Vec<String> = bfs[0].strategies().iter().map(|s| s.name()).collect();
        assert!(
            strategies.contains(&"frontier".to_string()),
            "{strategies:?}"
        );
    }
}
