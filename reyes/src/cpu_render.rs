//! The CPU reference of the whole GPU pipeline: the stage twins in `stages/` driven by a work
//! stack. The order of work differs from the GPU's, which cannot change the image: every sample
//! keeps the maximum of its keys.

use crate::frame::{FrameData, PatchItem};
use crate::image::FrameImage;
use crate::stages::{self, bound::Cull, bound::Decision};

/// The image plus what each stage did, in the GPU's terms (`stages::C_*` counters; executed
/// items per procedure: bound, splitu, splitv, diceshade, dicesmall).
pub struct CpuRender {
    pub image: FrameImage,
    pub counters: [u64; stages::COUNTERS],
    pub executed: [u64; 5],
}

impl CpuRender {
    /// Grids diced by either dice procedure.
    pub fn grids(&self) -> u64 {
        self.executed[3] + self.executed[4]
    }
}

pub fn render_cpu(data: &FrameData) -> CpuRender {
    let f = &data.frame;
    let spp = f.spp_x * f.spp_y;
    let mut samples = vec![0u64; f.width as usize * f.height as usize * spp as usize];
    let mut counters = [0u64; stages::COUNTERS];
    let mut executed = [0u64; 5];
    walk(data, &mut counters, &mut executed, |item, counters| {
        let (mps, culled) = stages::dice_shade::dice_shade(item, data, &mut samples);
        counters[stages::C_MICROPOLYGONS] += mps as u64;
        counters[stages::C_BACKFACE] += culled as u64;
    });
    let (rgba, depth) = stages::resolve::resolve(&samples, f.width, f.height, spp);
    CpuRender {
        image: FrameImage {
            width: f.width,
            height: f.height,
            rgba,
            depth,
        },
        counters,
        executed,
    }
}

/// The grids the pipeline dices, with Bound's rates and dilation filled in: the same items
/// the GPU dices (the decisions are the same f32 code), without shading or sampling. What
/// the accuracy metrics measure.
pub fn diced_items(data: &FrameData) -> Vec<PatchItem> {
    let mut items = Vec::new();
    walk(data, &mut [0; stages::COUNTERS], &mut [0; 5], |item, _| {
        items.push(*item)
    });
    items
}

/// Runs Bound and the splits to completion, counting as the GPU does, and hands every grid
/// to be diced to `dice`.
fn walk(
    data: &FrameData,
    counters: &mut [u64; stages::COUNTERS],
    executed: &mut [u64; 5],
    mut dice: impl FnMut(&PatchItem, &mut [u64; stages::COUNTERS]),
) {
    let f = &data.frame;
    let mut work: Vec<_> = data.items.clone();
    while let Some(item) = work.pop() {
        executed[0] += 1;
        match stages::bound::bound(&item, f, &data.patch_info[item.patch_id as usize]) {
            Decision::Cull(c) => {
                counters[match c {
                    Cull::Clip => stages::C_CULL_CLIP,
                    Cull::Offscreen => stages::C_CULL_OFFSCREEN,
                    Cull::Backface => stages::C_CULL_BACKFACE,
                }] += 1
            }
            Decision::Split { along_u, item, eye } => {
                counters[stages::C_EYE_SPLITS] += eye as u64;
                executed[if along_u { 1 } else { 2 }] += 1;
                for second in [false, true] {
                    work.push(stages::split::split_half(&item, along_u, second));
                }
            }
            Decision::Dice {
                item,
                depth_limited,
            } => {
                counters[stages::C_DEPTH_LIMIT] += depth_limited as u64;
                counters[stages::C_NEAR_CLIPPED] +=
                    (item.rates & stages::NEAR_CLIP_GRID != 0) as u64;
                counters[stages::C_MAX_DEPTH] =
                    counters[stages::C_MAX_DEPTH].max(item.splits() as u64);
                executed[if stages::is_small_grid(&item) { 4 } else { 3 }] += 1;
                dice(&item, counters);
            }
        }
    }
}
