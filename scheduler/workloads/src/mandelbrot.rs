//! Adaptive Mandelbrot: the Mariani-Silver algorithm (Mariani 1983; Silver's rectangle
//! subdivision as described in Peitgen & Saupe, *The Science of Fractal Images*, 1988). A
//! rectangle whose border pixels all have the same escape count ("dwell") is filled with that
//! count; otherwise its interior is split into four rectangles, or computed per pixel once the
//! rectangle is small. Work per rectangle is therefore irregular: cheap fills, expensive pixel
//! blocks, and subdivision whose depth depends on the image.
//!
//! Three procedures, 32 threads per item ([`MS_THREADS`]), one item type [`MandelRect`]:
//! - `ms_rect` computes the rectangle's border pixels with all its threads, reduces their minimum
//!   and maximum dwell in workgroup memory (`Procedure::shared`), and emits one `ms_fill` (uniform
//!   border), one `ms_pixels` (small) or up to four `ms_rect` (the interior's quadrants);
//! - `ms_fill` writes the dwell to every interior pixel;
//! - `ms_pixels` computes every interior pixel.
//!
//! Every pixel is written exactly once: a rectangle's border by its `ms_rect` item, its interior
//! by its fill, pixel block or children. The CPU reference is the brute-force image
//! ([`MandelParams::reference`]); the same subdivision runs on the CPU ([`MandelParams::mariani_silver`],
//! rayon over tiles) and yields the same item counts as the GPU.
//!
//! **Exact arithmetic.** The escape iteration is written with explicit `fma` in WGSL, in the
//! same order as the Rust twin, so that no compiler can contract `a * b + c` differently on
//! either side. But WGSL's (and Vulkan's `GLSL.std.450 Fma`) precision is only "inherited from a
//! multiply and an add": a device may or may not fuse it. NVIDIA fuses; Mesa 22.3's lavapipe
//! splits it into a rounded multiply and an add (measured: the unfused twin reproduces its images
//! bit for bit). So [`fma_is_fused`] tests the device with inputs on which the two differ, and
//! [`MandelParams::fused_fma`] tells the CPU twin which to compute (`f32::mul_add`, or `a * b + c`,
//! which Rust never contracts); [`MandelParams::for_gpu`] sets it. Images are then compared
//! exactly. Mariani-Silver itself is exact only where the border property holds (no detail
//! entirely inside a rectangle with a uniform border); the preset views are ones where it does in
//! both arithmetics, checked against the brute-force image.

use scheduler::bindings::UserBindings;
use scheduler::error::RunError;
use scheduler::gpu::Gpu;
use scheduler::procedure::{ItemType, Procedure};
use scheduler::program::{Program, Seed};
use scheduler::stats::RunStats;
use scheduler::strategy::Scheduler;

mod cpu;
pub use cpu::dwell;

/// Threads per item of every Mandelbrot procedure (a warp on NVIDIA).
pub const MS_THREADS: u32 = 32;
/// Largest initial tile side: a fill of a whole tile is `tile² / MS_THREADS` loop turns per
/// thread, which must stay far below lavapipe's 65,535-iteration loop cut.
pub const MAX_TILE: u32 = 1024;
/// Largest iteration limit (lavapipe cuts every loop at 65,535 turns).
pub const MAX_ITERATIONS: u32 = 60_000;

/// Which part of the complex plane the image shows: pixel `(px, py)` (row `py` from the top)
/// samples `c = (centre_re + (px - (W - 1) / 2) * scale, centre_im + ((H - 1) / 2 - py) * scale)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Real part of the image centre.
    pub centre_re: f32,
    /// Imaginary part of the image centre.
    pub centre_im: f32,
    /// Complex-plane units per pixel.
    pub scale: f32,
}

/// One Mandelbrot image to compute: size, view, iteration limit, subdivision settings.
#[derive(Debug, Clone, PartialEq)]
pub struct MandelParams {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The part of the complex plane shown.
    pub view: View,
    /// Iteration limit: a pixel that has not escaped after this many iterations has this dwell.
    pub max_iterations: u32,
    /// A non-uniform rectangle whose smaller side is at most this is computed per pixel instead
    /// of split (at least 3).
    pub min_side: u32,
    /// Side of the initial tiles (the seeds), `3..=MAX_TILE`; tiles at the right and bottom edge
    /// are clipped to the image.
    pub tile: u32,
    /// Whether the GPU's `fma` is fused, so the CPU twin must use `f32::mul_add` (true, the
    /// presets' default) or a rounded multiply and an add (false). [`MandelParams::for_gpu`] sets
    /// it from [`fma_is_fused`]; [`MandelRun::new`] refuses parameters that disagree with the device.
    pub fused_fma: bool,
}

/// The host twin of WGSL `MandelRect`: a rectangle of pixels and, for `ms_fill`, its dwell.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MandelRect {
    /// Left column, in pixels.
    pub x: u32,
    /// Top row, in pixels.
    pub y: u32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
    /// The uniform border's dwell (`ms_fill` only; 0 otherwise).
    pub dwell: u32,
}

/// The Mandelbrot program's procedures, in registration order (`--procedure-steps` names).
pub const PROCEDURES: [&str; 3] = ["ms_rect", "ms_fill", "ms_pixels"];

const RECT_WGSL: &str = "struct MandelRect { x: u32, y: u32, w: u32, h: u32, dwell: u32 }";

/// The host twin of WGSL `MandelCfg` (group 1, binding 1): the image and view at run time, so
/// one compiled program serves every size and view.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MandelCfg {
    /// [`MandelParams::width`].
    pub width: u32,
    /// [`MandelParams::height`].
    pub height: u32,
    /// [`MandelParams::max_iterations`].
    pub max_iterations: u32,
    /// [`MandelParams::min_side`].
    pub min_side: u32,
    /// `(width - 1) / 2`: the image centre's column, in pixels.
    pub half_w: f32,
    /// `(height - 1) / 2`: the image centre's row, in pixels.
    pub half_h: f32,
    /// [`View::scale`].
    pub scale: f32,
    /// [`View::centre_re`].
    pub centre_re: f32,
    /// [`View::centre_im`].
    pub centre_im: f32,
}

const CFG_WGSL: &str = "struct MandelCfg { width: u32, height: u32, max_iterations: u32, \
     min_side: u32, half_w: f32, half_h: f32, scale: f32, centre_re: f32, centre_im: f32 }";

/// An escape-count image, row-major, `width * height` dwells.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MandelImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Escape iteration counts (`max_iterations` for points that did not escape), row-major.
    pub dwell: Vec<u32>,
}

impl MandelImage {
    /// Pixels whose dwell differs from `other`'s (all of them if the sizes differ).
    pub fn differing_pixels(&self, other: &MandelImage) -> u64 {
        if (self.width, self.height) != (other.width, other.height) {
            return self.dwell.len().max(other.dwell.len()) as u64;
        }
        self.dwell
            .iter()
            .zip(&other.dwell)
            .filter(|(a, b)| a != b)
            .count() as u64
    }
}

/// How Mariani-Silver spent its work. The GPU and CPU subdivisions produce identical counts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MsWork {
    /// `ms_rect` items: rectangles whose border was computed (tiles included).
    pub rects: u64,
    /// `ms_fill` items: interiors filled from a uniform border.
    pub fills: u64,
    /// `ms_pixels` items: interiors computed per pixel.
    pub pixel_rects: u64,
    /// Pixels written by fills.
    pub filled_pixels: u64,
    /// Pixels whose dwell was iterated (borders and pixel blocks).
    pub computed_pixels: u64,
}

impl MsWork {
    fn add(mut self, o: MsWork) -> MsWork {
        self.rects += o.rects;
        self.fills += o.fills;
        self.pixel_rects += o.pixel_rects;
        self.filled_pixels += o.filled_pixels;
        self.computed_pixels += o.computed_pixels;
        self
    }
}

/// A GPU run's output: the image (compared with [`MandelParams::reference`]) and the work counts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MandelResult {
    /// The image the GPU wrote.
    pub image: MandelImage,
    /// Items per procedure and pixel counters of the GPU run.
    pub work: MsWork,
}

/// `result == reference` compares the image only: the brute-force reference has no work counts.
impl PartialEq<MandelImage> for MandelResult {
    fn eq(&self, other: &MandelImage) -> bool {
        self.image == *other
    }
}

/// Whether this device's WGSL `fma` is fused (one rounding) or a rounded multiply followed by an
/// add: one thread computes `fma(1 + 2^-12, 1 + 2^-12, -1)`, which is `2^-11 + 2^-24` fused and
/// `2^-11` unfused (the product's last bit is a tie that rounds to even). The inputs come from a
/// buffer so that no compiler can fold them. Any other answer is a [`RunError::Device`].
pub fn fma_is_fused(gpu: &Gpu) -> Result<bool, RunError> {
    const FMA_TEST: &str = "@group(0) @binding(0) var<storage, read_write> io: array<f32, 4>;\n\
        @compute @workgroup_size(1) fn main() { io[3] = fma(io[0], io[1], io[2]); }";
    let a = 1.0 + 2f32.powi(-12);
    let (fused, unfused) = (2f32.powi(-11) + 2f32.powi(-24), 2f32.powi(-11));
    debug_assert_eq!(a.mul_add(a, -1.0), fused);
    debug_assert_eq!(a * a - 1.0, unfused);
    let io = gpu.storage_buffer("fma probe", 4)?;
    gpu.queue
        .write_buffer(&io, 0, bytemuck::cast_slice(&[a, a, -1.0, 0.0]));
    let pipe = gpu.compute_pipeline("fma probe", FMA_TEST, "main")?;
    let bind = gpu.bind_buffers("fma probe", &pipe.get_bind_group_layout(0), &[&io]);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipe);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    gpu.submit(enc);
    let got = f32::from_bits(gpu.read_words(&io, 3, 1)?[0]);
    if got == fused {
        Ok(true)
    } else if got == unfused {
        Ok(false)
    } else {
        Err(RunError::Device(format!(
            "fma probe: fma(1 + 2^-12, 1 + 2^-12, -1) = {got:e}, neither fused ({fused:e}) nor \
             a rounded multiply and add ({unfused:e})"
        )))
    }
}

impl MandelParams {
    /// The benchmark view: a `size × size` image of the whole set (real part -2.2..0.7, span
    /// 2.9) at 1,024 iterations, 64-pixel tiles, per pixel at 16 pixels and below. Its
    /// Mariani-Silver image equals the brute-force one, in both `fma` arithmetics, at 256², 1024²
    /// and 4096² (checked on the CPU; the unit tests check 256²). Other sizes sample other
    /// points and are not checked: span 2.6 differed in 3 (unfused) / 5 (fused) pixels at 4096²,
    /// span 2.8 in 2 (fused) at 4096², span 2.7 in 2 (fused) at 1024².
    pub fn whole_set(size: u32) -> Self {
        MandelParams {
            width: size,
            height: size,
            view: View {
                centre_re: -0.75,
                centre_im: 0.0,
                scale: 2.9 / size as f32,
            },
            max_iterations: 1024,
            min_side: 16,
            tile: 64,
            fused_fma: true,
        }
    }

    /// A `size × size` zoom into the Seahorse Valley (filaments and spirals: more subdivision and
    /// more per-pixel blocks than [`MandelParams::whole_set`]), 2,048 iterations. Mariani-Silver
    /// is exact here at 64², 128² and 256² (checked, both arithmetics) but not at 1024², where 4
    /// (fused) / 13 (unfused) pixels differ from brute force: a test view, not a benchmark one.
    pub fn seahorse(size: u32) -> Self {
        MandelParams {
            width: size,
            height: size,
            view: View {
                centre_re: -0.7435,
                centre_im: 0.1314,
                scale: 0.02 / size as f32,
            },
            max_iterations: 2048,
            min_side: 16,
            tile: 64,
            fused_fma: true,
        }
    }

    /// These parameters in the arithmetic of `gpu`'s `fma` (see [`fma_is_fused`]).
    pub fn for_gpu(self, gpu: &Gpu) -> Result<Self, RunError> {
        Ok(MandelParams {
            fused_fma: fma_is_fused(gpu)?,
            ..self
        })
    }

    /// One line of every parameter, for reports.
    pub fn describe(&self) -> String {
        format!(
            "{}x{} centre=({},{}) scale={:e} iterations={} min_side={} tile={} fma={}",
            self.width,
            self.height,
            self.view.centre_re,
            self.view.centre_im,
            self.view.scale,
            self.max_iterations,
            self.min_side,
            self.tile,
            if self.fused_fma { "fused" } else { "unfused" }
        )
    }

    /// Checks the parameters the GPU code relies on.
    pub fn validate(&self) -> Result<(), RunError> {
        let bad = |m: String| Err(RunError::Program(format!("Mandelbrot: {m}")));
        if self.width == 0 || self.height == 0 {
            return bad("the image is empty".into());
        }
        if self.width.max(self.height) >= 1 << 24 {
            return bad("a side of 2^24 pixels or more is not exact in f32".into());
        }
        if !(1..=MAX_ITERATIONS).contains(&self.max_iterations) {
            return bad(format!("iterations must be 1..={MAX_ITERATIONS}"));
        }
        if self.min_side < 3 {
            return bad("the smallest rectangle side must be at least 3".into());
        }
        if !(3..=MAX_TILE).contains(&self.tile) {
            return bad(format!("the tile side must be 3..={MAX_TILE}"));
        }
        Ok(())
    }

    /// The run-time configuration the GPU reads (group 1, binding 1).
    pub fn cfg(&self) -> MandelCfg {
        MandelCfg {
            width: self.width,
            height: self.height,
            max_iterations: self.max_iterations,
            min_side: self.min_side,
            half_w: (self.width as f32 - 1.0) * 0.5,
            half_h: (self.height as f32 - 1.0) * 0.5,
            scale: self.view.scale,
            centre_re: self.view.centre_re,
            centre_im: self.view.centre_im,
        }
    }

    /// The initial tiles, row by row, clipped to the image.
    pub fn tiles(&self) -> Vec<MandelRect> {
        let t = self.tile;
        (0..self.height.div_ceil(t))
            .flat_map(|ty| {
                (0..self.width.div_ceil(t)).map(move |tx| MandelRect {
                    x: tx * t,
                    y: ty * t,
                    w: t.min(self.width - tx * t),
                    h: t.min(self.height - ty * t),
                    dwell: 0,
                })
            })
            .collect()
    }

    /// The program; it depends on nothing in the parameters (they travel in `MandelCfg`).
    pub fn program(&self) -> Result<Program, RunError> {
        let item = ItemType::new("MandelRect", RECT_WGSL);
        let user = UserBindings {
            wgsl: format!(
                "{CFG_WGSL}\n\
                 @group(1) @binding(0) var<storage, read_write> ms_out: array<u32>;\n\
                 @group(1) @binding(1) var<storage, read> ms_cfg: MandelCfg;\n\
                 // [0] pixels filled, [1] pixels iterated\n\
                 @group(1) @binding(2) var<storage, read_write> ms_count: array<atomic<u32>, 2>;\n\
                 const MS_T: u32 = {MS_THREADS}u;\n{MS_WGSL}"
            ),
            layout: vec![
                scheduler::storage_entry(0, false),
                scheduler::storage_entry(1, true),
                scheduler::storage_entry(2, false),
            ],
        };
        let rect = Procedure::new("ms_rect", item.clone(), MS_THREADS)
            .shared("atomic<u32>", 2)
            .emits("ms_rect", 4)
            .emits("ms_fill", 1)
            .emits("ms_pixels", 1)
            .body(RECT_BODY);
        let fill = Procedure::new("ms_fill", item.clone(), MS_THREADS).body(FILL_BODY);
        let pixels = Procedure::new("ms_pixels", item, MS_THREADS).body(PIXELS_BODY);
        Program::new(vec![rect, fill, pixels], user)
    }

    /// One `ms_rect` item per tile.
    pub fn seeds(&self) -> Vec<Seed> {
        vec![Seed::new("ms_rect", &self.tiles())]
    }
}

const MS_WGSL: &str = r#"
// The escape count of pixel p: the same fused operations in the same order as Rust `dwell`.
fn ms_dwell(p: vec2<u32>) -> u32 {
    let cr = fma(f32(p.x) - ms_cfg.half_w, ms_cfg.scale, ms_cfg.centre_re);
    let ci = fma(ms_cfg.half_h - f32(p.y), ms_cfg.scale, ms_cfg.centre_im);
    var x = 0.0;
    var y = 0.0;
    for (var n = 0u; n < ms_cfg.max_iterations; n++) {
        if fma(x, x, y * y) > 4.0 { return n; }
        let nx = fma(x, x, fma(-y, y, cr));
        y = fma(x + x, y, ci);
        x = nx;
    }
    return ms_cfg.max_iterations;
}
fn ms_put(p: vec2<u32>, d: u32) { ms_out[p.y * ms_cfg.width + p.x] = d; }
fn ms_border_count(w: u32, h: u32) -> u32 {
    if w == 0u || h == 0u { return 0u; }
    if h == 1u { return w; }
    if w == 1u { return h; }
    return 2u * w + 2u * h - 4u;
}
// Top row, bottom row, left column, right column.
fn ms_border_pixel(r: MandelRect, i: u32) -> vec2<u32> {
    if r.h == 1u { return vec2(r.x + i, r.y); }
    if r.w == 1u { return vec2(r.x, r.y + i); }
    if i < r.w { return vec2(r.x + i, r.y); }
    if i < 2u * r.w { return vec2(r.x + i - r.w, r.y + r.h - 1u); }
    let j = i - 2u * r.w;
    if j < r.h - 2u { return vec2(r.x, r.y + 1u + j); }
    return vec2(r.x + r.w - 1u, r.y + 1u + j - (r.h - 2u));
}
"#;

const RECT_BODY: &str = r#"
fn ms_rect_execute(item: MandelRect, inv: Invocation) {
    // This item's two words of workgroup memory: minimum and maximum border dwell.
    let s = inv.slot * 2u;
    if inv.thread == 0u {
        atomicStore(&ms_rect_shared[s], 0xffffffffu);
        atomicStore(&ms_rect_shared[s + 1u], 0u);
    }
    workgroupBarrier();
    var nb = 0u;
    if inv.live { nb = ms_border_count(item.w, item.h); }
    var lo = 0xffffffffu;
    var hi = 0u;
    for (var i = inv.thread; i < nb; i += MS_T) {
        let p = ms_border_pixel(item, i);
        let d = ms_dwell(p);
        ms_put(p, d);
        lo = min(lo, d);
        hi = max(hi, d);
    }
    atomicMin(&ms_rect_shared[s], lo);
    atomicMax(&ms_rect_shared[s + 1u], hi);
    workgroupBarrier();
    let lo_all = atomicLoad(&ms_rect_shared[s]);
    let hi_all = atomicLoad(&ms_rect_shared[s + 1u]);
    if !inv.live || inv.thread != 0u { return; }
    atomicAdd(&ms_count[1], nb);
    if item.w <= 2u || item.h <= 2u { return; }
    let inner = MandelRect(item.x + 1u, item.y + 1u, item.w - 2u, item.h - 2u, lo_all);
    if lo_all == hi_all {
        enqueue_ms_fill(inner);
    } else if min(item.w, item.h) <= ms_cfg.min_side {
        enqueue_ms_pixels(inner);
    } else {
        let w0 = inner.w / 2u;
        let h0 = inner.h / 2u;
        let xs = array<u32, 2>(inner.x, inner.x + w0);
        let ws = array<u32, 2>(w0, inner.w - w0);
        let ys = array<u32, 2>(inner.y, inner.y + h0);
        let hs = array<u32, 2>(h0, inner.h - h0);
        for (var b = 0u; b < 2u; b++) {
            for (var a = 0u; a < 2u; a++) {
                if ws[a] > 0u && hs[b] > 0u { enqueue_ms_rect(MandelRect(xs[a], ys[b], ws[a], hs[b], 0u)); }
            }
        }
    }
}
"#;

const FILL_BODY: &str = r#"
fn ms_fill_execute(item: MandelRect, inv: Invocation) {
    if !inv.live { return; }
    let n = item.w * item.h;
    for (var i = inv.thread; i < n; i += MS_T) {
        ms_put(vec2(item.x + i % item.w, item.y + i / item.w), item.dwell);
    }
    if inv.thread == 0u { atomicAdd(&ms_count[0], n); }
}
"#;

const PIXELS_BODY: &str = r#"
fn ms_pixels_execute(item: MandelRect, inv: Invocation) {
    if !inv.live { return; }
    let n = item.w * item.h;
    for (var i = inv.thread; i < n; i += MS_T) {
        let p = vec2(item.x + i % item.w, item.y + i / item.w);
        ms_put(p, ms_dwell(p));
    }
    if inv.thread == 0u { atomicAdd(&ms_count[1], n); }
}
"#;

/// The Mandelbrot workload's GPU resources: the image, its configuration, the pixel counters,
/// and their bind group (group 1).
pub struct MandelRun {
    /// The image computed by the next run.
    pub params: MandelParams,
    /// Its program ([`MandelParams::program`]).
    pub program: Program,
    out: wgpu::Buffer,
    cfg: wgpu::Buffer,
    count: wgpu::Buffer,
    bind: wgpu::BindGroup,
}

impl MandelRun {
    /// Validates `params` (also that `fused_fma` is this device's arithmetic), builds the program
    /// and allocates a `width × height` word image; an image larger than the device's storage
    /// binding limit is a [`RunError::Device`].
    pub fn new(gpu: &Gpu, params: MandelParams) -> Result<MandelRun, RunError> {
        params.validate()?;
        let fused = fma_is_fused(gpu)?;
        if fused != params.fused_fma {
            return Err(RunError::Program(format!(
                "Mandelbrot: the parameters say fused_fma = {}, but {}'s fma is {}fused, so the \
                 CPU reference would not match; build them with MandelParams::for_gpu",
                params.fused_fma,
                gpu.adapter_name(),
                if fused { "" } else { "not " }
            )));
        }
        let program = params.program()?;
        let out = gpu.storage_buffer(
            "mandelbrot image",
            params.width as u64 * params.height as u64,
        )?;
        let cfg = gpu.storage_buffer("mandelbrot cfg", size_of::<MandelCfg>() as u64 / 4)?;
        let count = gpu.storage_buffer("mandelbrot counters", 2)?;
        let bind = program.user.bind_group(gpu, &[&out, &cfg, &count])?;
        Ok(MandelRun {
            params,
            program,
            out,
            cfg,
            count,
            bind,
        })
    }

    /// Runs once (image and counters cleared first, so a lost item shows) and reads the image
    /// and the work counts back.
    pub fn run(
        &self,
        gpu: &Gpu,
        scheduler: &Scheduler,
    ) -> Result<(RunStats, MandelResult), RunError> {
        let p = &self.params;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.out, 0, None);
        enc.clear_buffer(&self.count, 0, None);
        gpu.submit(enc);
        gpu.queue
            .write_buffer(&self.cfg, 0, bytemuck::bytes_of(&p.cfg()));
        // The image and the counts come back with the run's last read-back.
        let reads = [
            (&self.out, 0, p.width as u64 * p.height as u64),
            (&self.count, 0, 2),
        ];
        let (stats, mut words) =
            scheduler.run_reading(gpu, &p.seeds(), Some(&self.bind), None, &reads)?;
        let count = words.pop().expect("the counts' range");
        let dwell = words.pop().expect("the image's range");
        let work = MsWork {
            rects: stats.executed[0],
            fills: stats.executed[1],
            pixel_rects: stats.executed[2],
            filled_pixels: count[0] as u64,
            computed_pixels: count[1] as u64,
        };
        let image = MandelImage {
            width: p.width,
            height: p.height,
            dwell,
        };
        Ok((stats, MandelResult { image, work }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scheduler::wgsl::struct_layout;

    #[test]
    fn procedures_are_named_as_listed() {
        let program = MandelParams::whole_set(64).program().unwrap();
        let names: Vec<&str> = program.procs.iter().map(|p| p.proc.name.as_str()).collect();
        assert_eq!(names, PROCEDURES);
    }

    fn small(w: u32, h: u32) -> MandelParams {
        MandelParams {
            width: w,
            height: h,
            max_iterations: 256,
            tile: 32,
            min_side: 6,
            ..MandelParams::whole_set(w)
        }
    }

    #[test]
    fn host_structs_match_the_wgsl_layout() {
        let r = struct_layout(RECT_WGSL, "MandelRect").unwrap();
        assert_eq!(r.size as usize, size_of::<MandelRect>());
        assert_eq!(r.members[4], ("dwell".into(), 16));
        let c = struct_layout(CFG_WGSL, "MandelCfg").unwrap();
        assert_eq!(c.size as usize, size_of::<MandelCfg>());
        assert_eq!(
            c.members[8],
            (
                "centre_im".into(),
                std::mem::offset_of!(MandelCfg, centre_im) as u32
            )
        );
    }

    #[test]
    fn invalid_parameters_are_refused() {
        for p in [
            MandelParams {
                tile: MAX_TILE + 1,
                ..small(64, 64)
            },
            MandelParams {
                min_side: 2,
                ..small(64, 64)
            },
            MandelParams {
                max_iterations: MAX_ITERATIONS + 1,
                ..small(64, 64)
            },
            small(0, 64),
        ] {
            assert!(p.validate().is_err(), "{}", p.describe());
        }
    }
}
