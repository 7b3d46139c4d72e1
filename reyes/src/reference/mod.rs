//! An f64 ground truth for what the renderer must draw, independent of any GPU code:
//! exact sample coverage of a scene's patches ([`coverage`]), the shared projection
//! convention ([`project`]), and the closed test surface `scenes/closed_blob.rib`
//! ([`closed`]).

pub mod closed;
pub mod exact;

pub use exact::{Coverage, coverage, pinholes, project};
