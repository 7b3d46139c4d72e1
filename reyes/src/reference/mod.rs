//! An f64 ground truth for what the renderer must draw, independent of any GPU code:
//! exact sample coverage of a scene's patches ([`coverage`]), the shared projection
//! convention ([`project`]), the closed test surfaces (`scenes/closed_blob.rib`, an exact
//! rational sphere: [`closed`]), and exact rational patch arithmetic ([`homogeneous`]).

pub mod closed;
pub mod exact;
pub mod homogeneous;
mod polygon;

pub use exact::{Coverage, coverage, pinholes, project};
