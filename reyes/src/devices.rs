//! Several devices in one process: the adapters that can render, the devices a `--devices`
//! selection opens, and one frame split into screen buckets over several devices, its image
//! assembled bit for bit as one device renders it.
//!
//! Each device has a thread of its own and takes the next bucket from a shared counter (a
//! queue that balances itself: a device that finishes early takes more); a bucket renders on
//! one device exactly as a bucket of [`GpuRenderer::render`] does (`crate::buckets`), and each
//! pixel belongs to exactly one bucket, so the assembled image equals one device's render.
//! Frames of a sequence are spread over the devices by the caller the same way (one queue of
//! frames; `reyes render --devices`, `reyes bench --devices`).
//!
//! A selection names adapters by their index in [`adapters`]' list; an index given twice
//! opens two logical devices on that adapter (each its own `wgpu::Device` and queue), which
//! is how the tests use two devices on the one lavapipe adapter.

use crate::frame::{FrameData, FrameUniforms, Tile};
use crate::gpu_render::{GpuFrame, GpuRenderer, TilePixels};
use crate::image::FrameImage;
use crate::stages::C_MAX_DEPTH;
use scheduler::{Gpu, RunError};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// Which devices to open: every adapter that can render, or adapters by index (repeats open
/// several devices on one adapter).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceSelection {
    /// Every adapter that has the features ([`usable_indices`]): the GPUs, or the CPU
    /// adapters when there is no GPU.
    All,
    /// Adapters by their index in [`adapters`], in this order; an index may repeat.
    List(Vec<usize>),
}

impl std::str::FromStr for DeviceSelection {
    type Err = String;

    /// `all`, or indices separated by commas (`0,1`; `0,0`: two devices on adapter 0).
    fn from_str(s: &str) -> Result<DeviceSelection, String> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("all") {
            return Ok(DeviceSelection::All);
        }
        let list = (s.split(','))
            .map(|p| {
                p.trim().parse::<usize>().map_err(|_| {
                    format!("`{p}` is not an adapter index (`all`, or indices such as `0,1`)")
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        if list.len() > MAX_DEVICES {
            return Err(format!(
                "{} devices: at most {MAX_DEVICES} may be opened",
                list.len()
            ));
        }
        Ok(DeviceSelection::List(list))
    }
}

/// The most devices one selection may open.
pub const MAX_DEVICES: usize = 64;

/// An adapter as wgpu enumerates it, and whether it can render.
pub struct AdapterEntry {
    /// Its index in the list (what a [`DeviceSelection::List`] names).
    pub index: usize,
    /// Name, backend, type, driver.
    pub info: wgpu::AdapterInfo,
    /// Required features it lacks; empty when it can render.
    pub missing: wgpu::Features,
    adapter: wgpu::Adapter,
}

impl AdapterEntry {
    /// Whether the adapter has every required feature.
    pub fn usable(&self) -> bool {
        self.missing.is_empty()
    }

    /// One line: index, name, backend, type, and what it lacks.
    pub fn describe(&self) -> String {
        let i = &self.info;
        let state = match self.usable() {
            true => "can render".to_string(),
            false => format!("skipped: lacks {:?}", self.missing),
        };
        format!(
            "{}: {} ({:?}, {:?}, driver {} {}): {state}",
            self.index, i.name, i.backend, i.device_type, i.driver, i.driver_info
        )
    }
}

/// Every adapter of `instance` (e.g. [`Gpu::instance_from_env`]: the backends of
/// `WGPU_BACKEND`), in wgpu's order, with the `required` features each lacks.
pub fn adapters(instance: &wgpu::Instance, required: wgpu::Features) -> Vec<AdapterEntry> {
    let all = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    (all.into_iter().enumerate())
        .map(|(index, adapter)| AdapterEntry {
            index,
            info: adapter.get_info(),
            missing: required - adapter.features(),
            adapter,
        })
        .collect()
}

/// The indices [`DeviceSelection::All`] opens: the usable adapters that are not CPUs, or the
/// usable CPU adapters (lavapipe, WARP) when no GPU can render: a CPU adapter beside GPUs
/// would only slow the queue's last frames.
pub fn usable_indices(list: &[AdapterEntry]) -> Vec<usize> {
    let usable = || list.iter().filter(|a| a.usable());
    let gpus: Vec<usize> = usable()
        .filter(|a| a.info.device_type != wgpu::DeviceType::Cpu)
        .map(|a| a.index)
        .collect();
    match gpus.is_empty() {
        true => usable().map(|a| a.index).collect(),
        false => gpus,
    }
}

/// A device opened for a selection: its adapter's index and the device.
pub struct OpenedDevice {
    /// Index of its adapter in [`adapters`].
    pub adapter: usize,
    /// The device.
    pub gpu: Gpu,
}

impl OpenedDevice {
    /// `#N adapter-name (backend)`, N being the adapter's index.
    pub fn name(&self) -> String {
        format!("#{} {}", self.adapter, self.gpu.adapter_name())
    }
}

/// Opens the devices of `selection` with the `required` features, in its order (the
/// adapters of [`Gpu::instance_from_env`]). Errors ([`RunError::NoAdapter`]): no adapter can
/// render, an index beyond the list, an adapter lacking a feature (named), or a device that
/// cannot be opened. The devices keep naga's loop bounding until their owner trusts their loops
/// ([`Gpu::trust_loops`]), as the `reyes` command does.
pub fn open(
    selection: &DeviceSelection,
    required: wgpu::Features,
) -> Result<Vec<OpenedDevice>, RunError> {
    let list = adapters(&Gpu::instance_from_env(), required);
    let indices = match selection {
        DeviceSelection::All => usable_indices(&list),
        DeviceSelection::List(l) => l.clone(),
    };
    if indices.is_empty() {
        let seen: Vec<String> = list.iter().map(AdapterEntry::describe).collect();
        return Err(RunError::NoAdapter(format!(
            "no adapter can render (adapters: {}). Install a Vulkan driver (on Debian: \
             `apt-get install -y mesa-vulkan-drivers` for lavapipe)",
            if seen.is_empty() {
                "none".into()
            } else {
                seen.join("; ")
            }
        )));
    }
    let mut out = Vec::new();
    for i in indices {
        let Some(entry) = list.get(i) else {
            return Err(RunError::NoAdapter(format!(
                "--devices: no adapter {i}; there are {} (`reyes devices` lists them)",
                list.len()
            )));
        };
        if !entry.usable() {
            return Err(RunError::NoAdapter(format!(
                "--devices: adapter {}",
                entry.describe()
            )));
        }
        let gpu = Gpu::from_adapter(entry.adapter.clone(), required)?;
        out.push(OpenedDevice { adapter: i, gpu });
    }
    Ok(out)
}

/// The buckets of a frame split over `devices`: under a memory budget the budget's buckets
/// ([`crate::buckets::plan`]) when they are several; else horizontal strips of whole rows,
/// four per device (so that a device finding its strips empty takes more), each a multiple
/// of [`crate::buckets::MIN_BUCKET_SIDE`] rows high but the last.
pub fn split_tiles(f: &FrameUniforms, budget: Option<u64>, devices: usize) -> Vec<Tile> {
    let plan = crate::buckets::plan(f, budget);
    if plan.len() > 1 || devices <= 1 {
        return plan;
    }
    let side = crate::buckets::MIN_BUCKET_SIDE;
    let wanted = (4 * devices as u32).max(1);
    let h = f.height.div_ceil(wanted).div_ceil(side).max(1) * side;
    (0..f.height)
        .step_by(h as usize)
        .map(|y0| Tile {
            x0: 0,
            y0,
            w: f.width,
            h: h.min(f.height - y0),
        })
        .collect()
}

/// What one device did for a split frame.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceShare {
    /// The device's name ([`OpenedDevice::name`]).
    pub device: String,
    /// Buckets it rendered (recut quarters counted).
    pub buckets: u32,
    /// Its GPU time (scheduler runs and resolves), when timestamps exist.
    pub gpu_ms: Option<f64>,
    /// Its host time from the start of the frame to its last bucket read back.
    pub wall_ms: f64,
}

/// One frame rendered over several devices.
pub struct SplitFrame {
    /// The frame: the assembled image, counters and run statistics summed over the devices
    /// (peaks and the split depth are maxima), `wall_ms` the frame's host time.
    pub frame: GpuFrame,
    /// Each device's share, in the order of the devices given.
    pub shares: Vec<DeviceShare>,
}

/// A device's failure while rendering a split frame: which device, the bucket it was on.
#[derive(Debug, thiserror::Error)]
#[error("device {device}: bucket {tile:?}: {error}")]
pub struct DeviceError {
    /// The device's name.
    pub device: String,
    /// The bucket it had taken last, if any.
    pub tile: Option<Tile>,
    /// What failed.
    #[source]
    pub error: RunError,
}

/// Renders `data` split into buckets ([`split_tiles`]) over `devices`, each with its
/// renderer (`(name, gpu, renderer)`), one thread per device taking the next bucket from a
/// shared counter; the image is assembled from the buckets read back, identical bit for bit
/// to [`GpuRenderer::render`] on one device. Errors: the first device to fail, with the
/// bucket it was on (the others stop taking buckets).
pub fn render_split(
    devices: &[(&str, &Gpu, &GpuRenderer)],
    data: &FrameData,
) -> Result<SplitFrame, DeviceError> {
    let start = Instant::now();
    let f = &data.frame;
    let tiles = split_tiles(f, data.memory_budget, devices.len());
    let largest = tiles.iter().map(|t| t.w as u64 * t.h as u64).max().unwrap();
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let results: Mutex<Vec<Option<DeviceResult>>> =
        Mutex::new((0..devices.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for (d, &(name, gpu, renderer)) in devices.iter().enumerate() {
            let (tiles, next, failed, results) = (&tiles, &next, &failed, &results);
            s.spawn(move || {
                let mut last = None;
                let mut take = || {
                    if failed.load(Ordering::Relaxed) {
                        return None;
                    }
                    let t = tiles.get(next.fetch_add(1, Ordering::Relaxed)).copied();
                    last = t.or(last);
                    t
                };
                let r = renderer.render_tiles(gpu, data, largest, &mut take, true);
                let r = r
                    .map(|(frame, pixels)| (frame, pixels, start.elapsed().as_secs_f64() * 1e3))
                    .map_err(|error| {
                        failed.store(true, Ordering::Relaxed);
                        DeviceError {
                            device: name.to_string(),
                            tile: last,
                            error,
                        }
                    });
                results.lock().unwrap_or_else(|p| p.into_inner())[d] = Some(r);
            });
        }
    });
    let results = results.into_inner().unwrap_or_else(|p| p.into_inner());
    let mut done = Vec::new();
    for r in results {
        done.push(r.expect("every device thread stores its result")?);
    }
    let mut image = FrameImage {
        width: f.width,
        height: f.height,
        rgba: vec![[0.0; 4]; (f.width * f.height) as usize],
        depth: vec![0.0; (f.width * f.height) as usize],
    };
    let mut shares = Vec::new();
    let mut frame: Option<GpuFrame> = None;
    for ((name, _, _), (part, pixels, wall_ms)) in devices.iter().zip(done) {
        for p in &pixels {
            place(&mut image, p);
        }
        shares.push(DeviceShare {
            device: name.to_string(),
            buckets: part.buckets,
            gpu_ms: gpu_ms(&part),
            wall_ms,
        });
        frame = Some(match frame {
            None => part,
            Some(sum) => absorb(sum, part),
        });
    }
    let mut frame = frame.expect("at least one device");
    frame.image = image;
    frame.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(SplitFrame { frame, shares })
}

/// A device thread's result: its part of the frame, its buckets' pixels, its wall ms.
type DeviceResult = Result<(GpuFrame, Vec<TilePixels>, f64), DeviceError>;

/// A frame's GPU ms: scheduler runs plus resolves, when both were timed.
pub fn gpu_ms(f: &GpuFrame) -> Option<f64> {
    f.run.gpu_ms.zip(f.resolve_gpu_ms).map(|(a, b)| a + b)
}

/// Writes a bucket's pixels into the image.
fn place(image: &mut FrameImage, p: &TilePixels) {
    let t = p.tile;
    for y in 0..t.h as usize {
        let dst = (t.y0 as usize + y) * image.width as usize + t.x0 as usize;
        let src = y * t.w as usize;
        let n = t.w as usize;
        image.rgba[dst..dst + n].copy_from_slice(&p.rgba[src..src + n]);
        image.depth[dst..dst + n].copy_from_slice(&p.depth[src..src + n]);
    }
}

/// Two devices' parts of one frame as one: counts and times summed, peaks and the split
/// depth maxima.
fn absorb(mut a: GpuFrame, b: GpuFrame) -> GpuFrame {
    for (k, (x, y)) in a.counters.iter_mut().zip(b.counters).enumerate() {
        *x = if k == C_MAX_DEPTH {
            (*x).max(y)
        } else {
            *x + y
        };
    }
    if b.runs > 0 {
        if a.runs == 0 {
            a.run = b.run;
        } else {
            a.run.absorb(&b.run);
        }
    }
    a.resolve_gpu_ms = a.resolve_gpu_ms.zip(b.resolve_gpu_ms).map(|(x, y)| x + y);
    a.sample_bytes = a.sample_bytes.max(b.sample_bytes);
    a.buckets += b.buckets;
    a.buckets_recut += b.buckets_recut;
    a.runs += b.runs;
    a.batches_split += b.batches_split;
    a.peak_working_bytes = a.peak_working_bytes.max(b.peak_working_bytes);
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn selections_parse() {
        assert_eq!("all".parse(), Ok(DeviceSelection::All));
        assert_eq!(" 0, 1 ".parse(), Ok(DeviceSelection::List(vec![0, 1])));
        assert_eq!("0,0".parse(), Ok(DeviceSelection::List(vec![0, 0])));
        assert!("".parse::<DeviceSelection>().is_err());
        assert!("0,x".parse::<DeviceSelection>().is_err());
        assert!("-1".parse::<DeviceSelection>().is_err());
    }

    #[test]
    fn split_tiles_partition_the_image() {
        let scene = crate::scene::builtin_teapot();
        for (w, h, devices) in [(301, 203, 2), (64, 20, 3), (7680, 4320, 2), (17, 5, 8)] {
            let o = crate::frame::RenderOptions {
                width: Some(w),
                height: Some(h),
                ..Default::default()
            };
            let f = FrameData::new(&scene, &o).unwrap().frame;
            let tiles = split_tiles(&f, None, devices);
            assert!(
                tiles.len() >= devices.min(h.div_ceil(16) as usize),
                "{w}x{h}"
            );
            let mut hits = vec![0u8; (w * h) as usize];
            for t in &tiles {
                for y in t.y0..t.y0 + t.h {
                    for x in t.x0..t.x0 + t.w {
                        hits[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(hits.iter().all(|&n| n == 1), "{w}x{h}");
        }
    }
}
