//! `reyes drift [SCENE] [--width N --height N] [--paths N] [--seed N] [--json]`: how far the
//! GPU's f32 splits drift from exact f64 subdivision, per split depth, in pixels (see
//! `reyes_accuracy::drift`), and how deep the scene really splits (CPU pipeline).

use crate::cli::DriftCmd;
use crate::error::CliError;
use reyes::cpu_render::render_cpu;
use reyes::frame::{FrameData, RenderOptions};
use reyes_accuracy::drift::{self, PathOptions};

/// Runs the subcommand.
pub fn main(a: DriftCmd) -> Result<(), CliError> {
    let (width, height, as_json) = (a.width, a.height, a.json);
    let o = PathOptions {
        random_paths: a.paths,
        seed: a.seed,
    };
    let scene_path = a.scene;
    let (scene, _) = crate::setup::load_scene(scene_path.as_deref())?;
    // The table names a file by its path, not its stem.
    let name = match &scene_path {
        Some(p) if p.as_os_str() != "teapot" => p.display().to_string(),
        _ => "teapot".to_string(),
    };
    let options = RenderOptions {
        width: Some(width),
        height: Some(height),
        ..Default::default()
    };
    let data = FrameData::new(&scene, &options)?;
    // The depth the CPU pipeline reaches, and the same split tree walked with exact twins.
    let cpu = render_cpu(&data);
    let cpu_depth = cpu.counters[reyes::stages::C_MAX_DEPTH];
    // Grids: the items of every dicing procedure (those after Bound, SplitU, SplitV).
    let cpu_grids: u64 = cpu.executed[3..].iter().sum();
    let tree = drift::tree_drift(&scene, &data);
    if tree.max_depth as u64 != cpu_depth || tree.grids != cpu_grids {
        return Err(CliError::DriftDisagrees {
            tree_depth: tree.max_depth as u64,
            cpu_depth,
            tree_grids: tree.grids,
            cpu_grids,
        });
    }
    let rows = drift::path_drift(&scene, &data, &o);
    if as_json {
        let v = serde_json::json!({
            "scene": name,
            "width": width,
            "height": height,
            "random_paths_per_patch": o.random_paths,
            "seed": o.seed,
            "paths": rows.iter().map(|r| r.json()).collect::<Vec<_>>(),
            "split_tree": tree.json(),
        });
        reyes_cli::outln!("{}", serde_json::to_string(&v).unwrap());
        return Ok(());
    }
    reyes_cli::outln!(
        "{name} at {width}x{height}: {} patches, {} paths each (2 alternating + {} random), \
         distances in pixels",
        scene.patches.len(),
        2 + o.random_paths,
        o.random_paths
    );
    reyes_cli::outln!("\nseeded split paths:");
    reyes_cli::out!("{}", drift::table(&rows));
    reyes_cli::outln!(
        "\nthe renderer's own split tree (cpu_render): max split depth {}, {} grids, {} depth-limited",
        tree.max_depth,
        tree.grids,
        tree.depth_limited
    );
    reyes_cli::out!("{}", drift::table(&tree.rows));
    Ok(())
}
