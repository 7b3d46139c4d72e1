//! Accuracy measurements of the renderer against f64 references.

#![warn(missing_docs)]

pub mod drift;
pub mod exact_image;
pub mod geometry;
pub mod holes;
pub mod image_error;
pub mod measure;
pub mod parallel;
pub mod pareto;
pub mod plot;
pub mod surface;
