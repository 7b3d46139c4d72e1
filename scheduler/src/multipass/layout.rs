//! Host twin of the mp_ctrl and params word layouts in `shaders/multipass.wgsl`.
#![allow(dead_code)] // the whole host twin of the layout: not every word is read by the host

pub const CSTRIDE: usize = 8;
pub const C_COUNT: usize = 0;
pub const C_PEAK: usize = 1;
pub const C_EXEC: usize = 2;
pub const C_EMITS: usize = 3;
pub const C_NEXT: usize = 4;
pub const C_RUN: usize = 5;
pub const C_KEEP: usize = 6;
pub const C_WGS: usize = 7;
pub const G_ROUNDS: usize = 0;
pub const G_ERROR: usize = 1;
pub const G_ERR_A: usize = 2;
pub const G_ERR_B: usize = 3;
pub const G_HALT: usize = 4;
pub const G_PLANNED: usize = 5;
pub const G_PARTIAL: usize = 6;
pub const G_DONE: usize = 7;
pub const G_WGS: usize = 8;
pub const G_K: usize = 9;
pub const G_CHUNK: usize = 10;
pub const ERR_EMIT: u32 = 1;
pub const ERR_OVERFLOW: u32 = 2;
pub const ERR_ROOM: u32 = 3;
/// Words of params per queue: capacity, first word of its region, at its limit.
pub const P_QSTRIDE: usize = 4;

pub fn ctrl_words(nq: usize) -> usize {
    nq * CSTRIDE + 12
}
pub fn c(q: usize, i: usize) -> usize {
    q * CSTRIDE + i
}
pub fn g(nq: usize, i: usize) -> usize {
    nq * CSTRIDE + i
}
