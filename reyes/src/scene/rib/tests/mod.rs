//! Tests of the RIB interpreter, one file per concern like the interpreter's.

mod archives;
mod camera;
mod displacement;
mod frames;
mod fuzz;
mod hostile;
mod limits;
mod motion;
mod nupatch;
mod objects;
mod patches;
mod polygons;
mod primvars;
mod quadrics;
mod shading;
mod state;
mod syntax;

use super::parse_rib;
use crate::scene::{Scene, SceneError};
use glam::DVec3;

pub(super) fn parse(s: &str) -> Scene {
    match parse_rib(s, "t.rib") {
        Ok(s) => s,
        Err(e) => panic!("unexpected error: {e}"),
    }
}

pub(super) fn err(s: &str) -> String {
    parse_rib(s, "t.rib")
        .expect_err("expected an error")
        .to_string()
}

pub(super) fn world(body: &str) -> String {
    format!("WorldBegin\n{body}\nWorldEnd\n")
}

/// Corners (0,0,0), (1,0,0), (0,1,0), (1,1,0).
pub(super) const QUAD: &str = "Patch \"bilinear\" \"P\" [0 0 0  1 0 0  0 1 0  1 1 0]";

pub(super) fn close(a: DVec3, b: DVec3) -> bool {
    a.distance(b) < 1e-9
}

/// 16 points of a wavy 4x4 grid, as RIB numbers.
pub(super) fn grid_numbers(nu: usize, nv: usize) -> (Vec<DVec3>, String) {
    let pts: Vec<DVec3> = (0..nu * nv)
        .map(|k| {
            let (c, r) = ((k % nu) as f64, (k / nu) as f64);
            DVec3::new(c, r, (c * 0.9).sin() * (r * 0.7 + 0.3).cos())
        })
        .collect();
    let s = pts
        .iter()
        .map(|p| format!("{} {} {}", p.x, p.y, p.z))
        .collect::<Vec<_>>()
        .join(" ");
    (pts, s)
}
