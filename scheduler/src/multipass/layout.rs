//! Host twin of the mp_ctrl and params word layouts in `shaders/multipass.wgsl`.
#![allow(dead_code)] // the whole host twin of the layout: not every word is read by the host

pub const CSTRIDE: usize = 9;
pub const C_PEAK: usize = 0;
pub const C_EXEC: usize = 1;
pub const C_EMITS: usize = 2;
/// `C_APPEND + w`: items appended to count window `w` (0, 1, 2).
pub const C_APPEND: usize = 3;
/// `C_CARRY + w`: inputs carried, unrun, to the front of window `w`.
pub const C_CARRY: usize = 6;
pub const G_ROUNDS: usize = 0;
pub const G_ERROR: usize = 1;
pub const G_ERR_A: usize = 2;
pub const G_ERR_B: usize = 3;
pub const G_HALT: usize = 4;
pub const G_PARTIAL: usize = 5;
pub const G_RAN: usize = 6;
pub const G_BASE: usize = 7;
pub const G_CHUNK: usize = 8;
pub const ERR_EMIT: u32 = 1;
pub const ERR_OVERFLOW: u32 = 2;
pub const ERR_ROOM: u32 = 3;
/// Words of params per queue: capacity, first word of its region, at its limit.
pub const P_QSTRIDE: usize = 4;
/// Count windows: a round's inputs, its appends, and the next round's appends (cleared).
pub const WINDOWS: usize = 3;

pub fn ctrl_words(nq: usize) -> usize {
    nq * CSTRIDE + 12
}
pub fn c(q: usize, i: usize) -> usize {
    q * CSTRIDE + i
}
pub fn g(nq: usize, i: usize) -> usize {
    nq * CSTRIDE + i
}
/// Inputs of queue `q` in count window `w` of `ctrl`: carried plus appended.
pub fn window_count(ctrl: &[u32], q: usize, w: usize) -> u32 {
    ctrl[c(q, C_CARRY + w)] + ctrl[c(q, C_APPEND + w)]
}
/// The window of the inputs pending after a chunk whose first round read window `base` and
/// of which `ctrl`'s `G_RAN` rounds ran (the next round's, or the refused round's).
pub fn pending_window(nq: usize, ctrl: &[u32], base: usize) -> usize {
    (base + ctrl[g(nq, G_RAN)] as usize) % WINDOWS
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl::wgsl_const;

    /// Every word index of `shaders/multipass.wgsl`'s mp_ctrl layout equals its host twin's.
    #[test]
    fn the_host_twin_matches_the_wgsl_layout() {
        let wgsl = super::super::wgsl::TEMPLATE;
        let twins: [(&str, usize); 18] = [
            ("CSTRIDE", CSTRIDE),
            ("C_PEAK", C_PEAK),
            ("C_EXEC", C_EXEC),
            ("C_EMITS", C_EMITS),
            ("C_APPEND", C_APPEND),
            ("C_CARRY", C_CARRY),
            ("G_ROUNDS", G_ROUNDS),
            ("G_ERROR", G_ERROR),
            ("G_ERR_A", G_ERR_A),
            ("G_ERR_B", G_ERR_B),
            ("G_HALT", G_HALT),
            ("G_PARTIAL", G_PARTIAL),
            ("G_RAN", G_RAN),
            ("G_BASE", G_BASE),
            ("G_CHUNK", G_CHUNK),
            ("ERR_EMIT", ERR_EMIT as usize),
            ("ERR_OVERFLOW", ERR_OVERFLOW as usize),
            ("ERR_ROOM", ERR_ROOM as usize),
        ];
        for (name, host) in twins {
            assert_eq!(wgsl_const(wgsl, name), Some(host), "{name}");
        }
        // The globals (G_*) fit the words after the queues' strides; the windows, a stride.
        assert!(G_CHUNK < ctrl_words(1) - CSTRIDE);
        const { assert!(C_CARRY + WINDOWS <= CSTRIDE) };
    }
}
