//! The `--stats` JSON of a frame: what each stage did and what it cost.

use crate::frame::{FrameData, PatchItem};
use crate::gpu_render::{GpuFrame, PROCEDURES};
use crate::stages as s;
use serde_json::{Value, json};

pub fn frame_stats(data: &FrameData, g: &GpuFrame, adapter: &str, warnings: &[String]) -> Value {
    let c = &g.counters;
    let ex = &g.run.executed;
    let covered = g.image.covered_pixels();
    let item_bytes = std::mem::size_of::<PatchItem>() as u64;
    let peak_queue_bytes: u64 = g.run.peak_occupancy.iter().map(|n| n * item_bytes).sum();
    let schedule_ms = g.run.gpu_ms;
    let total_ms = schedule_ms.zip(g.resolve_gpu_ms).map(|(a, b)| a + b);
    let f = &data.frame;
    json!({
        "strategy": g.run.strategy,
        "adapter": adapter,
        "width": f.width,
        "height": f.height,
        "pixel_samples": [f.spp_x, f.spp_y],
        "mp_size_px": f.mp_size,
        "bound_px": if f.bound_px > 0.0 { json!(f.bound_px) } else { Value::Null },
        "patches_in": data.items.len(),
        "bounds": ex[0],
        "splits": ex[1] + ex[2],
        "splits_u": ex[1],
        "splits_v": ex[2],
        "eye_splits": c[s::C_EYE_SPLITS],
        "culls": {
            "clip": c[s::C_CULL_CLIP],
            "offscreen": c[s::C_CULL_OFFSCREEN],
            "backface_patches": c[s::C_CULL_BACKFACE],
            "backface_micropolygons": c[s::C_BACKFACE],
        },
        "depth_limited": c[s::C_DEPTH_LIMIT],
        "near_clipped_grids": c[s::C_NEAR_CLIPPED],
        "grids_diced": ex[3] + ex[4],
        "grids_small": ex[4],
        "micropolygons": c[s::C_MICROPOLYGONS],
        "covered_pixels": covered,
        "micropolygons_per_covered_pixel": c[s::C_MICROPOLYGONS] as f64 / covered.max(1) as f64,
        "max_split_depth": c[s::C_MAX_DEPTH],
        "executed": PROCEDURES.iter().zip(ex).map(|(p, n)| (p.to_string(), json!(n))).collect::<serde_json::Map<_, _>>(),
        "gpu_ms_per_stage": stage_times(g),
        "gpu_ms": total_ms,
        "wall_ms": g.wall_ms,
        "launches": g.run.launches,
        "workgroups": g.run.workgroups,
        "rounds": g.run.rounds,
        "queue_growths": g.run.queue_growths,
        "peak_queue_items": g.run.peak_occupancy,
        "peak_queue_bytes": peak_queue_bytes,
        "queue_bytes_allocated": g.run.queue_bytes,
        "sample_bytes": g.sample_bytes,
        "memory_budget": data.memory_budget,
        "buckets": g.buckets,
        "buckets_recut": g.buckets_recut,
        "scheduler_runs": g.runs,
        "batches_split": g.batches_split,
        "peak_working_bytes": g.peak_working_bytes,
        "warnings": warnings,
    })
}

/// GPU ms per stage: every procedure and the queue work when multi-pass timed them
/// (`--stage-times`), else the scheduler run as one; the resolve pass always.
fn stage_times(g: &GpuFrame) -> Value {
    let mut m = serde_json::Map::new();
    let per_stage = &g.run.stage_gpu_ms;
    if per_stage.len() == PROCEDURES.len() + 1 {
        for (name, ms) in PROCEDURES.iter().chain(&["queue_work"]).zip(per_stage) {
            m.insert(name.to_string(), json!(ms));
        }
    } else {
        m.insert("schedule".into(), json!(g.run.gpu_ms));
        m.insert(
            "note".into(),
            json!("stages interleave inside one megakernel launch; multipass --stage-times times each procedure"),
        );
    }
    m.insert("resolve".into(), json!(g.resolve_gpu_ms));
    Value::Object(m)
}
