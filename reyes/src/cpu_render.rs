//! The CPU reference of the whole GPU pipeline: the stage twins in `stages/` driven by a work
//! stack. The order of work differs from the GPU's, which cannot change the image: every sample
//! keeps the maximum of its keys.

use crate::buckets;
use crate::frame::{FrameData, FrameUniforms, PatchItem};
use crate::image::FrameImage;
use crate::stages::{self, bound::Cull, bound::Decision, hiz};

/// The image plus what each stage did, in the GPU's terms (`stages::C_*` counters; executed
/// items per procedure: bound, splitu, splitv, diceshade, dicesmall).
pub struct CpuRender {
    /// The resolved image, as the GPU path gives it.
    pub image: FrameImage,
    /// The stages' counters, indexed by `stages::C_*`.
    pub counters: [u64; stages::COUNTERS],
    /// Items executed per procedure: bound, splitu, splitv, diceshade, dicesmall.
    pub executed: [u64; 5],
}

impl CpuRender {
    /// Grids diced by either dice procedure.
    pub fn grids(&self) -> u64 {
        self.executed[3] + self.executed[4]
    }
}

/// Renders `data` as the GPU does, in the same screen buckets under
/// [`FrameData::memory_budget`] (`buckets::plan`), so the sample buffer held at once is one
/// bucket's; the image does not depend on the buckets.
pub fn render_cpu(data: &FrameData) -> CpuRender {
    let f = &data.frame;
    let spp = f.spp_x * f.spp_y;
    let pixels = f.width as usize * f.height as usize;
    let mut image = FrameImage {
        width: f.width,
        height: f.height,
        rgba: vec![[0.0; 4]; pixels],
        depth: vec![0.0; pixels],
    };
    let mut counters = [0u64; stages::COUNTERS];
    let mut executed = [0u64; 5];
    for tile in buckets::plan(f, data.memory_budget) {
        // Without a budget the one bucket is the whole image: `data` as it is.
        let bucket = match data.memory_budget {
            None => std::borrow::Cow::Borrowed(data),
            Some(_) => std::borrow::Cow::Owned(FrameData {
                frame: f.with_tile(tile),
                materials: data.materials.clone(),
                lights: data.lights.clone(),
                patch_info: data.patch_info.clone(),
                primvars: data.primvars.clone(),
                items: (data.items.iter())
                    .filter(|i| {
                        let info = &data.patch_info[i.patch_id as usize];
                        let w = stages::item_weights(i, info, &data.primvars);
                        buckets::may_reach(f, i, w.as_ref(), tile)
                    })
                    .copied()
                    .collect(),
                memory_budget: data.memory_budget,
                background: data.background,
            }),
        };
        let mut samples = vec![0u64; tile.w as usize * tile.h as usize * spp as usize];
        // With occlusion culling, as the GPU: the passes of `hiz::passes`, each after the first
        // tested against the depth pyramid of what the passes before it drew.
        let occlusion = bucket.frame.occlusion != hiz::OCCLUSION_OFF;
        let (items, starts) = match occlusion {
            true => hiz::passes(&bucket, &bucket.items, tile),
            false => (bucket.items.clone(), vec![0]),
        };
        for (k, &start) in starts.iter().enumerate() {
            let end = starts.get(k + 1).copied().unwrap_or(items.len());
            let pyramid = (k > 0).then(|| hiz::build(&bucket.frame, &samples));
            let f = match pyramid {
                Some(_) => FrameUniforms {
                    occlusion: hiz::OCCLUSION_TEST,
                    ..bucket.frame
                },
                None => bucket.frame,
            };
            walk_items(
                &bucket,
                &f,
                items[start..end].to_vec(),
                pyramid.as_ref(),
                &mut counters,
                &mut executed,
                |item, counters| {
                    let (mps, culled) = stages::dice_shade::dice_shade(item, &bucket, &mut samples);
                    counters[stages::C_MICROPOLYGONS] += mps as u64;
                    counters[stages::C_BACKFACE] += culled as u64;
                },
            );
        }
        let (rgba, depth) =
            stages::resolve::resolve(&samples, tile.w, tile.h, spp, data.background);
        for row in 0..tile.h as usize {
            let (src, dst) = (
                row * tile.w as usize,
                (tile.y0 as usize + row) * f.width as usize + tile.x0 as usize,
            );
            let n = tile.w as usize;
            image.rgba[dst..dst + n].copy_from_slice(&rgba[src..src + n]);
            image.depth[dst..dst + n].copy_from_slice(&depth[src..src + n]);
        }
    }
    CpuRender {
        image,
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
    dice: impl FnMut(&PatchItem, &mut [u64; stages::COUNTERS]),
) {
    let items = data.items.clone();
    walk_items(data, &data.frame, items, None, counters, executed, dice)
}

/// [`walk`] from `items` under the uniforms `f` (`data`'s, perhaps with another
/// `occlusion`), Bound testing against `hiz` when `f` asks for it.
fn walk_items(
    data: &FrameData,
    f: &FrameUniforms,
    items: Vec<PatchItem>,
    hiz: Option<&hiz::Hiz>,
    counters: &mut [u64; stages::COUNTERS],
    executed: &mut [u64; 5],
    mut dice: impl FnMut(&PatchItem, &mut [u64; stages::COUNTERS]),
) {
    let mut work = items;
    while let Some(item) = work.pop() {
        executed[0] += 1;
        let info = &data.patch_info[item.patch_id as usize];
        match stages::bound::bound_against(&item, f, info, &data.primvars, hiz) {
            Decision::Cull(c) => {
                counters[match c {
                    Cull::Clip => stages::C_CULL_CLIP,
                    Cull::Offscreen => stages::C_CULL_OFFSCREEN,
                    Cull::Backface => stages::C_CULL_BACKFACE,
                    Cull::Occluded => stages::C_CULL_OCCLUDED,
                    Cull::Trimmed => stages::C_CULL_TRIMMED,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::RenderOptions;

    /// Under a memory budget the CPU twin renders in the GPU's buckets, holding one bucket's
    /// samples at a time, and makes the same image bit for bit.
    #[test]
    fn buckets_make_the_same_image() {
        let scene = crate::scene::builtin_teapot();
        let o = RenderOptions {
            width: Some(80),
            height: Some(60),
            ..Default::default()
        };
        let whole = render_cpu(&FrameData::new(&scene, &o).unwrap());
        let budget = Some(16 << 10);
        let data = FrameData::new(
            &scene,
            &RenderOptions {
                memory_budget: budget,
                ..o
            },
        )
        .unwrap();
        assert!(buckets::plan(&data.frame, budget).len() > 4);
        let cut = render_cpu(&data);
        assert!(whole.image.rgba.iter().any(|p| p[3] > 0.0));
        assert!(whole.image.rgba == cut.image.rgba, "rgba differs");
        assert!(whole.image.depth == cut.image.depth, "depth differs");
        assert_eq!(
            whole.counters[stages::C_MICROPOLYGONS] > 0,
            cut.counters[stages::C_MICROPOLYGONS] > 0
        );
    }
}
