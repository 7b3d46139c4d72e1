//! The `--stats` JSON of a frame ([`FrameStats`]): what each stage did and what it cost. Typed
//! (`serde` derive), so a mistyped or missing key is a compile error rather than a silent
//! null; the keys, units and meanings are tabled in docs/reyes.md (*Statistics*).

use crate::frame::{FrameData, PatchItem, RasterMode};
use crate::gpu_render::GpuFrame;
use crate::stages as s;
use serde::{Deserialize, Serialize};

/// `raster` of statistics JSON that has no `raster` key: `bbox`.
pub fn default_raster() -> String {
    RasterMode::BoundingBox.name().to_string()
}

/// What one GPU frame did and cost. Counts are of the whole frame (every bucket); times in
/// milliseconds; sizes in bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    /// The scheduling strategy (`megakernel`, `multipass`, `multipass-host`).
    pub strategy: String,
    /// The GPU adapter's name.
    pub adapter: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel, [x, y].
    pub pixel_samples: [u32; 2],
    /// Target micropolygon edge (px).
    pub mp_size_px: f64,
    /// Fixed-bound dicing's screen bound (px); null for adaptive dicing.
    pub bound_px: Option<f64>,
    /// Micropolygon rasterization (`--raster`): `bbox` or `nearest` (`RasterMode::name`);
    /// `bbox` when read from JSON without the key.
    #[serde(default = "default_raster")]
    pub raster: String,
    /// Root patches of the scene.
    pub patches_in: usize,
    /// Bytes of the scene's tables that grow with its patches: root items, patch infos and
    /// the primitive-variable table ([`crate::frame::FrameData::table_bytes`]); 0 when read
    /// from JSON without the key.
    #[serde(default)]
    pub table_bytes: u64,
    /// Bound procedure executions.
    pub bounds: u64,
    /// Splits (`splits_u + splits_v`).
    pub splits: u64,
    /// Splits along u (SplitU executions).
    pub splits_u: u64,
    /// Splits along v (SplitV executions).
    pub splits_v: u64,
    /// Splits forced by the near plane.
    pub eye_splits: u64,
    /// Pieces and micropolygons culled, by reason.
    pub culls: Culls,
    /// Grids diced at the split limit (coarser than asked).
    pub depth_limited: u64,
    /// Grids crossing the near plane after the allowed eye splits, diced and clipped.
    pub near_clipped_grids: u64,
    /// Grids diced (`diceshade` plus `dicesmall` executions).
    pub grids_diced: u64,
    /// Grids diced by the small-grid procedure.
    pub grids_small: u64,
    /// Micropolygons shaded and sampled.
    pub micropolygons: u64,
    /// Pixels with any coverage.
    pub covered_pixels: usize,
    /// `micropolygons / covered_pixels`.
    pub micropolygons_per_covered_pixel: f64,
    /// Deepest split level reached.
    pub max_split_depth: u64,
    /// Executions per procedure.
    pub executed: Executed,
    /// GPU ms per stage ([`StageTimes`]).
    pub gpu_ms_per_stage: StageTimes,
    /// GPU time of the scheduler run plus the resolve pass; null without timestamp queries.
    /// `reyes measure`: the median over its timed frames.
    pub gpu_ms: Option<f64>,
    /// Host time of the frame (`reyes measure`: the median over its timed frames).
    pub wall_ms: f64,
    /// Compute dispatches.
    pub launches: u64,
    /// Workgroups of the megakernel launch; 0 for the multi-passes, whose dispatches are sized
    /// round by round.
    pub workgroups: u32,
    /// Multi-pass rounds (0 for the megakernel).
    pub rounds: u64,
    /// Times a queue was reallocated larger.
    pub queue_growths: u64,
    /// Multi-pass rounds that took only part of a queue (its output would not fit).
    pub partial_rounds: u64,
    /// Megakernel: live items set aside on the host and run later, because queues at their
    /// limits could not hold the work's breadth (`scheduler::RunStats::parked_items`).
    pub parked_items: u64,
    /// Most items held at once, per queue (in `executed`'s order).
    pub peak_queue_items: Vec<u64>,
    /// `peak_queue_items` in bytes (`size_of::<PatchItem>()`, 224, per item), summed.
    pub peak_queue_bytes: u64,
    /// Bytes of queue storage allocated.
    pub queue_bytes_allocated: u64,
    /// Bytes of the sample buffer (one bucket's).
    pub sample_bytes: u64,
    /// `--memory-budget` (bytes); null without one.
    pub memory_budget: Option<u64>,
    /// Screen buckets rendered (1 without a memory budget).
    pub buckets: u32,
    /// Buckets cut again because their queues outgrew the budget.
    pub buckets_recut: u32,
    /// Scheduler runs (buckets and batches).
    pub scheduler_runs: u32,
    /// Root batches split because their queues would not fit.
    pub batches_split: u32,
    /// Largest working memory (sample buffer plus queues) at any point, bytes.
    pub peak_working_bytes: u64,
    /// The scene file's, the scene's and the frame's warnings (`reyes::warnings`).
    pub warnings: Vec<String>,
    /// `reyes render --runs`: each timed frame's times; absent elsewhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub runs: Option<RunSummary>,
    /// Motion blur and depth of field: how time and the lens were sampled; absent for a
    /// still pinhole frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uvt: Option<UvtStats>,
    /// `reyes render --compare-to`: the image error against the reference; absent elsewhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_error: Option<ImageErrorStats>,
    /// `reyes render --devices`: the device that rendered this frame of a sequence (each
    /// frame on one device), or the frame's buckets split over the devices (one entry each);
    /// absent without `--devices`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub devices: Option<Vec<DeviceStats>>,
}

/// One device's part in a frame (`reyes render --devices`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceStats {
    /// Its position in the `--devices` list (0, 1, ...).
    pub slot: usize,
    /// `#N name (backend)`: N its adapter's index (`reyes devices`).
    pub device: String,
    /// Frames it rendered (1 for the device of a frame of a sequence; 1 for each device of
    /// a split frame, which each rendered a part of).
    pub frames: u32,
    /// Screen buckets it rendered.
    pub buckets: u32,
    /// Its GPU ms (scheduler runs and resolves), when timestamps exist.
    pub gpu_ms: Option<f64>,
    /// Its host ms: from the frame's start to its last bucket read back.
    pub wall_ms: f64,
}

/// How a frame with motion blur or depth of field sampled time and the lens.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UvtStats {
    /// `simple`, `interleave` or `bbox` (`Sampling::name`).
    pub sampling: String,
    /// Interleave UVT's tile side K, pixels.
    pub il_tile: u32,
    /// Interleave UVT's number of permutations P.
    pub il_perms: u32,
    /// Root patches that move over the shutter.
    pub moving_patches: usize,
    /// Focal length (px) times lens radius: the circle of confusion's scale (0: no depth of
    /// field).
    pub coc_scale_px: f64,
}

/// The image error against a reference image (`reyes::accuracy::image_error`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageErrorStats {
    /// The reference file.
    pub reference: String,
    /// PSNR in dB over 8-bit sRGB composited over black (null when identical: infinite).
    pub psnr_db: f64,
    /// Mean of FLIP's error map, in [0, 1].
    pub flip_mean: f64,
}

/// Patches and micropolygons culled, by reason.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Culls {
    /// Pieces wholly outside the near/far range.
    pub clip: u64,
    /// Pieces wholly off screen.
    pub offscreen: u64,
    /// One-sided patches facing away.
    pub backface_patches: u64,
    /// Micropolygons of one-sided surfaces facing away.
    pub backface_micropolygons: u64,
    /// Pieces hidden behind what was already drawn (occlusion culling in Bound).
    pub occluded: u64,
    /// Pieces wholly cut away by trim curves (`TrimCurve`; culled in Bound).
    #[serde(default)]
    pub trimmed: u64,
}

/// Executions of each procedure (the names of `gpu_render::PROCEDURES`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Executed {
    /// Bound executions.
    pub bound: u64,
    /// SplitU executions.
    pub splitu: u64,
    /// SplitV executions.
    pub splitv: u64,
    /// DiceShade executions.
    pub diceshade: u64,
    /// DiceSmall (small-grid dicing) executions.
    pub dicesmall: u64,
}

/// GPU ms per stage: every procedure and the queue work when multi-pass timed them
/// (`--stage-times`), else the scheduler run as one; the resolve pass always. Null times:
/// the adapter has no timestamp queries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum StageTimes {
    /// Every procedure timed apart (either multi-pass with `--stage-times`).
    PerStage {
        /// GPU ms of Bound.
        bound: f64,
        /// GPU ms of SplitU.
        splitu: f64,
        /// GPU ms of SplitV.
        splitv: f64,
        /// GPU ms of DiceShade.
        diceshade: f64,
        /// GPU ms of DiceSmall.
        dicesmall: f64,
        /// The device-driven multi-pass's round planning (`mp_plan`); 0 for the host-driven
        /// one, whose host plans the rounds.
        queue_work: f64,
        /// GPU ms of the resolve pass.
        resolve: Option<f64>,
    },
    /// The scheduler run timed as one.
    Whole {
        /// GPU ms of the scheduler run.
        schedule: Option<f64>,
        /// Why the stages are not timed apart: only the megakernel's, whose stages share one
        /// launch (multi-pass without `--stage-times` has none).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        note: Option<String>,
        /// GPU ms of the resolve pass.
        resolve: Option<f64>,
    },
}

/// Median, median absolute deviation and every value of a time over the timed frames (ms).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MedianMad {
    /// Median.
    pub median: f64,
    /// Median absolute deviation from the median.
    pub mad: f64,
    /// Every value, in run order.
    pub all: Vec<f64>,
}

impl MedianMad {
    /// `None` for no values.
    pub fn of(v: Vec<f64>) -> Option<MedianMad> {
        if v.is_empty() {
            return None;
        }
        let (median, mad) = scheduler::stats::median_and_mad(&v);
        Some(MedianMad {
            median,
            mad,
            all: v,
        })
    }
}

/// `reyes render --runs N`: the timed frames' GPU and wall ms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Timed frames.
    pub count: usize,
    /// Null without timestamp queries.
    pub gpu_ms: Option<MedianMad>,
    /// Host ms of each timed frame.
    pub wall_ms: Option<MedianMad>,
}

impl RunSummary {
    /// From each run's (GPU ms, wall ms).
    pub fn of(times: &[(Option<f64>, f64)]) -> RunSummary {
        RunSummary {
            count: times.len(),
            gpu_ms: MedianMad::of(times.iter().filter_map(|t| t.0).collect()),
            wall_ms: MedianMad::of(times.iter().map(|t| t.1).collect()),
        }
    }
}

/// The statistics of GPU frame `g` of `data`, rendered on `adapter`, with `warnings`.
pub fn frame_stats(
    data: &FrameData,
    g: &GpuFrame,
    adapter: &str,
    warnings: &[String],
) -> FrameStats {
    let c = &g.counters;
    let ex = &g.run.executed;
    let executed = |i: usize| ex.get(i).copied().unwrap_or(0);
    let covered = g.image.covered_pixels();
    let item_bytes = std::mem::size_of::<PatchItem>() as u64;
    let peak_queue_bytes: u64 = g.run.peak_occupancy.iter().map(|n| n * item_bytes).sum();
    let f = &data.frame;
    FrameStats {
        strategy: g.run.strategy.clone(),
        adapter: adapter.to_string(),
        width: f.width,
        height: f.height,
        pixel_samples: [f.spp_x, f.spp_y],
        mp_size_px: f.mp_size as f64,
        bound_px: (f.bound_px > 0.0).then_some(f.bound_px as f64),
        raster: RasterMode::from_gpu_code(f.raster).name().to_string(),
        patches_in: data.items.len(),
        table_bytes: data.table_bytes(),
        bounds: executed(0),
        splits: executed(1) + executed(2),
        splits_u: executed(1),
        splits_v: executed(2),
        eye_splits: c[s::C_EYE_SPLITS],
        culls: Culls {
            clip: c[s::C_CULL_CLIP],
            offscreen: c[s::C_CULL_OFFSCREEN],
            backface_patches: c[s::C_CULL_BACKFACE],
            backface_micropolygons: c[s::C_BACKFACE],
            occluded: c[s::C_CULL_OCCLUDED],
            trimmed: c[s::C_CULL_TRIMMED],
        },
        depth_limited: c[s::C_DEPTH_LIMIT],
        near_clipped_grids: c[s::C_NEAR_CLIPPED],
        grids_diced: executed(3) + executed(4),
        grids_small: executed(4),
        micropolygons: c[s::C_MICROPOLYGONS],
        covered_pixels: covered,
        micropolygons_per_covered_pixel: c[s::C_MICROPOLYGONS] as f64 / covered.max(1) as f64,
        max_split_depth: c[s::C_MAX_DEPTH],
        executed: Executed {
            bound: executed(0),
            splitu: executed(1),
            splitv: executed(2),
            diceshade: executed(3),
            dicesmall: executed(4),
        },
        gpu_ms_per_stage: stage_times(g),
        gpu_ms: g.run.gpu_ms.zip(g.resolve_gpu_ms).map(|(a, b)| a + b),
        wall_ms: g.wall_ms,
        launches: g.run.launches,
        workgroups: g.run.workgroups,
        rounds: g.run.rounds,
        queue_growths: g.run.queue_growths,
        partial_rounds: g.run.partial_rounds,
        parked_items: g.run.parked_items,
        peak_queue_items: g.run.peak_occupancy.clone(),
        peak_queue_bytes,
        queue_bytes_allocated: g.run.queue_bytes,
        sample_bytes: g.sample_bytes,
        memory_budget: data.memory_budget,
        uvt: (f.uvt != crate::frame::UVT_OFF).then(|| UvtStats {
            sampling: match f.uvt {
                crate::frame::UVT_INTERLEAVE => "interleave",
                crate::frame::UVT_BBOX => "bbox",
                _ => "simple",
            }
            .to_string(),
            il_tile: f.il_tile,
            il_perms: f.il_perms,
            moving_patches: (data.patch_info.iter())
                .filter(|i| i.flags & crate::frame::PATCH_MOVING != 0)
                .count(),
            coc_scale_px: f.coc_scale as f64,
        }),
        image_error: None,
        buckets: g.buckets,
        buckets_recut: g.buckets_recut,
        scheduler_runs: g.runs,
        batches_split: g.batches_split,
        peak_working_bytes: g.peak_working_bytes,
        warnings: warnings.to_vec(),
        runs: None,
        devices: None,
    }
}

fn stage_times(g: &GpuFrame) -> StageTimes {
    match g.run.stage_gpu_ms[..] {
        [bound, splitu, splitv, diceshade, dicesmall, queue_work] => StageTimes::PerStage {
            bound,
            splitu,
            splitv,
            diceshade,
            dicesmall,
            queue_work,
            resolve: g.resolve_gpu_ms,
        },
        _ => StageTimes::Whole {
            schedule: g.run.gpu_ms,
            note: whole_note(&g.run.strategy),
            resolve: g.resolve_gpu_ms,
        },
    }
}

/// The note beside a scheduler run timed as one: the megakernel's stages interleave in one
/// launch and cannot be timed apart; other strategies (multi-pass without `--stage-times`) can,
/// so they carry none.
fn whole_note(strategy: &str) -> Option<String> {
    (strategy == "megakernel").then(|| {
        "stages interleave inside one megakernel launch; multipass or multipass-host with \
         --stage-times times each procedure"
            .into()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu_render::PROCEDURES;

    /// The typed names follow the procedures' (a renamed procedure must rename its keys).
    #[test]
    fn procedure_keys_are_the_procedures_names() {
        let e = Executed {
            bound: 0,
            splitu: 1,
            splitv: 2,
            diceshade: 3,
            dicesmall: 4,
        };
        let v = serde_json::to_value(&e).unwrap();
        let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
        let mut want: Vec<&str> = PROCEDURES.to_vec();
        want.sort();
        assert_eq!(keys, want);
        for (i, p) in PROCEDURES.iter().enumerate() {
            assert_eq!(v[p], i as u64);
        }
        let t = StageTimes::PerStage {
            bound: 0.0,
            splitu: 1.0,
            splitv: 2.0,
            diceshade: 3.0,
            dicesmall: 4.0,
            queue_work: 5.0,
            resolve: None,
        };
        let v = serde_json::to_value(&t).unwrap();
        for (i, p) in PROCEDURES.iter().chain(&["queue_work"]).enumerate() {
            assert_eq!(v[p], i as f64);
        }
        // Untagged: each shape reads back as itself.
        let back: StageTimes = serde_json::from_value(v).unwrap();
        assert_eq!(back, t);
        let w = StageTimes::Whole {
            schedule: Some(1.5),
            note: Some("n".into()),
            resolve: Some(0.5),
        };
        let back: StageTimes = serde_json::from_str(&serde_json::to_string(&w).unwrap()).unwrap();
        assert_eq!(back, w);
    }

    /// Only the megakernel explains why its stages are not timed apart; a multi-pass run timed
    /// as one writes no note (a new user read the megakernel's note in multipass stats).
    #[test]
    fn only_the_megakernel_carries_the_schedule_note() {
        assert!(
            whole_note("megakernel")
                .unwrap()
                .contains("megakernel launch")
        );
        for s in ["multipass", "multipass-host"] {
            assert_eq!(whole_note(s), None, "{s}");
            let w = StageTimes::Whole {
                schedule: Some(1.0),
                note: whole_note(s),
                resolve: None,
            };
            let v = serde_json::to_value(&w).unwrap();
            assert!(v.get("note").is_none(), "{s}: {v}");
            assert_eq!(serde_json::from_value::<StageTimes>(v).unwrap(), w);
        }
    }

    #[test]
    fn run_summary_of_times() {
        let r = RunSummary::of(&[(Some(2.0), 5.0), (None, 3.0), (Some(4.0), 4.0)]);
        assert_eq!(r.count, 3);
        assert_eq!(r.gpu_ms.as_ref().unwrap().all, [2.0, 4.0]);
        assert_eq!(r.wall_ms.as_ref().unwrap().median, 4.0);
        assert!(RunSummary::of(&[(None, 1.0)]).gpu_ms.is_none());
    }
}
