//! Adaptive Mandelbrot (`workloads::mandelbrot`, Mariani-Silver) as a suite
//! workload: the whole set at square sizes. Each size is put in the device's `fma` arithmetic
//! when prepared ([`ScheduledProblem::for_device`]), so its brute-force reference is the image
//! this device must produce exactly.

use crate::scale::Scale;
use crate::strategy::GpuConfig;
use crate::workload::{ProblemWorkload, ScheduledProblem};
use scheduler::{Gpu, Program, RunError, RunStats, Scheduler};
use workloads::mandelbrot::{MandelParams, MandelResult, MandelRun};

/// Iterations of the small sizes: lavapipe cuts a megakernel invocation's loops at 65,535 turns
/// in all (docs/scheduler.md, section 4), so its dwell loops stay short.
pub const SMALL_ITERATIONS: u32 = 256;

impl ScheduledProblem for MandelParams {
    /// The image and the Mariani-Silver work counts.
    type Output = MandelResult;
    type Run = MandelRun;

    fn for_device(&self, gpu: &Gpu) -> Result<MandelParams, RunError> {
        self.clone().for_gpu(gpu)
    }

    fn describe(&self) -> String {
        MandelParams::describe(self)
    }

    /// The brute-force image (every pixel iterated) with the counts of the same subdivision on
    /// the CPU: a run must match both, so a lost or repeated item shows even where the image
    /// would not.
    fn reference(&self) -> MandelResult {
        MandelResult {
            image: MandelParams::reference(self),
            work: self.mariani_silver().work,
        }
    }

    fn cpu(&self) -> MandelResult {
        self.mariani_silver()
    }

    /// Items executed: rectangles subdivided, filled and computed per pixel.
    fn items(out: &MandelResult) -> u64 {
        out.work.rects + out.work.fills + out.work.pixel_rects
    }

    fn new_run(&self, gpu: &Gpu) -> Result<MandelRun, RunError> {
        MandelRun::new(gpu, self.clone())
    }

    fn program(run: &MandelRun) -> &Program {
        &run.program
    }

    fn run(
        run: &MandelRun,
        gpu: &Gpu,
        scheduler: &Scheduler,
    ) -> Result<(RunStats, MandelResult), RunError> {
        run.run(gpu, scheduler)
    }
}

/// The suite's views, smallest first: `MandelParams::whole_set` at the sizes where its
/// Mariani-Silver image is exact (256², 1024², 4096² as documented; the small ones, at
/// [`SMALL_ITERATIONS`], checked by this module's test).
pub fn views(scale: Scale) -> Vec<MandelParams> {
    match scale {
        Scale::Small => [64, 128]
            .map(|s| MandelParams {
                max_iterations: SMALL_ITERATIONS,
                ..MandelParams::whole_set(s)
            })
            .to_vec(),
        Scale::Full => [256, 1024, 4096].map(MandelParams::whole_set).to_vec(),
    }
}

/// The suite workload `mandelbrot`, sized `WxH`.
pub fn suite_workload(scale: Scale, config: GpuConfig) -> ProblemWorkload<MandelParams> {
    let sizes = views(scale).into_iter().map(|p| (label(&p), p)).collect();
    ProblemWorkload::new("mandelbrot", sizes, config)
}

/// One whole-set image of the command line's side: `mandelbrot`, one size.
pub fn single_workload(size: u32, config: GpuConfig) -> ProblemWorkload<MandelParams> {
    let p = MandelParams::whole_set(size);
    ProblemWorkload::new("mandelbrot", vec![(label(&p), p)], config)
}

fn label(p: &MandelParams) -> String {
    format!("{}x{}", p.width, p.height)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The small views are ones where Mariani-Silver is exact in both `fma` arithmetics, so
    /// the suite's reference is reachable on any device.
    #[test]
    fn small_views_are_exact_in_both_arithmetics() {
        for p in views(Scale::Small) {
            for fused_fma in [false, true] {
                let p = MandelParams {
                    fused_fma,
                    ..p.clone()
                };
                let r = ScheduledProblem::reference(&p);
                let cpu = p.mariani_silver();
                assert_eq!(cpu.image.differing_pixels(&r.image), 0, "{}", p.describe());
                assert_eq!(cpu, r, "{}", p.describe());
            }
        }
    }
}
