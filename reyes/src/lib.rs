//! Real-time Reyes on the `scheduler` crate: bicubic Bezier patch scenes (RIB, Newell, BPT)
//! bounded, split, diced, shaded and sampled on the GPU by either scheduling strategy, with a
//! CPU twin of every stage as the reference.

pub mod cpu_render;
pub mod frame;
pub mod gpu_render;
pub mod image;
pub mod reference;
pub mod scene;
pub mod shaders;
pub mod stages;
pub mod stats;
