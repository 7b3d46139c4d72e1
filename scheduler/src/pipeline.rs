//! Small wgpu helpers shared by the strategies: storage bindings, pipelines, bind groups.

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::program::Program;

pub(crate) use crate::bindings::storage_entry;

/// Group 0 (the scheduler's, from `entries`) and group 1 (the user's, if any), and one compute
/// pipeline per entry point of `source`.
pub struct Kernels {
    pub group0: wgpu::BindGroupLayout,
    /// Group 2, for the entry points that write indirect dispatch arguments: the buffer must not
    /// be bound to the dispatches that read it as arguments.
    pub group2: Option<wgpu::BindGroupLayout>,
    pub pipelines: Vec<wgpu::ComputePipeline>,
    pub has_user_group: bool,
}

impl Kernels {
    pub fn new(
        gpu: &Gpu,
        program: &Program,
        label: &str,
        source: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
        entry_points: &[&str],
        group2: Option<(&[wgpu::BindGroupLayoutEntry], &[&str])>,
    ) -> Result<Kernels, RunError> {
        let module = gpu.shader(label, source)?;
        let group0 = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            });
        let user = program.user.bind_group_layout(gpu);
        let g2 = group2.map(|(entries, _)| {
            gpu.device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("indirect args"),
                    entries,
                })
        });
        let layouts = [Some(&group0), user.as_ref()];
        let layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: if user.is_some() {
                    &layouts
                } else {
                    &layouts[..1]
                },
                immediate_size: 0,
            });
        let layouts2 = [Some(&group0), user.as_ref(), g2.as_ref()];
        let layout2 = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &layouts2,
                immediate_size: 0,
            });
        let uses2 = |ep: &str| group2.is_some_and(|(_, eps)| eps.contains(&ep));
        let create = |ep: &str| {
            let start = std::time::Instant::now();
            let p = gpu
                .device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(ep),
                    layout: Some(if uses2(ep) { &layout2 } else { &layout }),
                    module: &module,
                    entry_point: Some(ep),
                    compilation_options: Default::default(),
                    cache: None,
                });
            crate::gpu::log_pipeline_time(label, ep, start);
            p
        };
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(entry_points.len());
        let pipelines = if threads <= 1 {
            entry_points.iter().map(|ep| create(ep)).collect()
        } else {
            in_parallel(entry_points, threads, create)
        };
        Ok(Kernels {
            group0,
            group2: g2,
            pipelines,
            has_user_group: user.is_some(),
        })
    }

    pub fn bind_group0(&self, gpu: &Gpu, buffers: &[(u32, &wgpu::Buffer)]) -> wgpu::BindGroup {
        gpu.bind_buffers_at("scheduler group 0", &self.group0, buffers)
    }

    /// Checks that the user supplied a bind group exactly when the program declared one.
    pub fn check_user_group(&self, user: Option<&wgpu::BindGroup>) -> Result<(), RunError> {
        match (self.has_user_group, user.is_some()) {
            (true, false) => Err(RunError::Program(
                "the program declares user bindings but the run got no bind group".into(),
            )),
            (false, true) => Err(RunError::Program(
                "the run got a user bind group but the program declares no user bindings".into(),
            )),
            _ => Ok(()),
        }
    }
}

/// `f` of every item, on `threads` threads that each take the next item not yet taken (the
/// drivers' pipeline compiles differ in length by 10x), in the items' order. Pipeline creation
/// may run on several threads at once (wgpu's `Device` is `Sync`; Vulkan lets pipelines be
/// created concurrently): on lavapipe, which turns each entry point's SPIR-V into NIR on the
/// calling thread, this divides multi-pass's pipeline creation by about the core count.
fn in_parallel<T: Send>(items: &[&str], threads: usize, f: impl Fn(&str) -> T + Sync) -> Vec<T> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<(usize, T)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(item) = items.get(i) else {
                            return mine;
                        };
                        mine.push((i, f(item)));
                    }
                })
            })
            .collect();
        (workers.into_iter())
            .flat_map(|w| w.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, t)| t).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item once, in order, whatever the thread count.
    #[test]
    fn in_parallel_keeps_the_items_order() {
        let items = ["a", "bb", "ccc", "dddd", "eeeee"];
        for threads in 1..=7 {
            let got = in_parallel(&items, threads, |s| s.len());
            assert_eq!(got, [1, 2, 3, 4, 5], "{threads} threads");
        }
    }
}
