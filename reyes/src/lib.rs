pub fn placeholder() {}
pub mod scene;
