//! The split tree (`workloads::tree`) as a suite workload: one workload per preset,
//! its sizes by number of roots.

use crate::scale::Scale;
use crate::strategy::GpuConfig;
use crate::workload::{ProblemWorkload, ScheduledProblem};
use scheduler::{Gpu, Program, RunError, RunStats, Scheduler};
use workloads::tree::{Fanout, TreeParams, TreePreset, TreeResult, TreeRun};

impl ScheduledProblem for TreeParams {
    type Output = TreeResult;
    type Run = TreeRun;

    fn describe(&self) -> String {
        TreeParams::describe(self)
    }

    fn procedure_steps(gpu: &Gpu) -> Vec<(String, u32)> {
        workloads::tree::megakernel_procedure_steps(gpu)
    }

    fn local_queues(&self) -> bool {
        self.megakernel_local_queues()
    }

    fn local_workgroup_bytes(&self, gpu: &Gpu, workgroup_size: u32) -> u32 {
        self.megakernel_local_workgroup_bytes(gpu, workgroup_size)
    }

    fn workgroup_share(&self, gpu: &Gpu, local_workgroup_bytes: u32) -> (u32, u32) {
        self.megakernel_workgroup_share(gpu, local_workgroup_bytes)
    }

    fn reference(&self) -> TreeResult {
        TreeParams::reference(self)
    }

    fn cpu(&self) -> TreeResult {
        self.cpu_parallel()
    }

    fn items(out: &TreeResult) -> u64 {
        out.items()
    }

    fn new_run(&self, gpu: &Gpu) -> Result<TreeRun, RunError> {
        TreeRun::new(gpu, self.clone())
    }

    fn program(run: &TreeRun) -> &Program {
        &run.program
    }

    fn run(
        run: &TreeRun,
        gpu: &Gpu,
        scheduler: &Scheduler,
    ) -> Result<(RunStats, TreeResult), RunError> {
        run.run(gpu, scheduler)
    }

    /// Same payload and the same declared fan-out: the compiled program is the same (a larger
    /// declared fan-out would serve too, but reserves more room and so is not the same run).
    fn retarget(&self, run: &mut TreeRun) -> bool {
        fanout_k(run.params()) == fanout_k(self)
            && run.params().payload_words == self.payload_words
            && run.set_params(self.clone()).is_ok()
    }
}

fn fanout_k(p: &TreeParams) -> u32 {
    match p.fanout {
        Fanout::Fixed(k) | Fanout::Uniform(k) => k,
    }
}

/// Roots of each suite size of a preset, smallest first. `Full` ends at (or, for the cheap
/// shapes, past) the preset's own size; `Small` keeps lavapipe on two cores to seconds.
pub fn roots(preset: TreePreset, scale: Scale) -> Vec<u32> {
    use TreePreset::*;
    match (scale, preset) {
        (Scale::Small, Binary | HeavyWork) => vec![1, 4],
        (Scale::Small, Irregular) => vec![2, 8],
        (Scale::Small, Deep) => vec![50, 200],
        (Scale::Small, LargePayload) => vec![1, 2],
        (Scale::Full, Binary | HeavyWork) => vec![4, 16, 64, 256],
        (Scale::Full, Irregular) => vec![16, 64, 256],
        (Scale::Full, Deep) => vec![1250, 5000, 20_000],
        (Scale::Full, LargePayload) => vec![4, 16, 64],
    }
}

/// The suite workload of one preset: `tree-<preset>`.
pub fn preset_workload(
    preset: TreePreset,
    scale: Scale,
    config: GpuConfig,
) -> ProblemWorkload<TreeParams> {
    let sizes = roots(preset, scale)
        .into_iter()
        .map(|roots| {
            (
                format!("roots={roots}"),
                TreeParams {
                    roots,
                    ..preset.params()
                },
            )
        })
        .collect();
    ProblemWorkload::new(format!("tree-{}", preset.name()), sizes, config)
}

/// One tree of the command line's choosing: `tree`, one size.
pub fn single_workload(params: TreeParams, config: GpuConfig) -> ProblemWorkload<TreeParams> {
    ProblemWorkload::new("tree", vec![("given".into(), params)], config)
}
