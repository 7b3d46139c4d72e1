//! Host twin of the ctrl and params word layouts in `shaders/megakernel_state.wgsl`.
//! A test compiles the shader and checks each constant against these. The words every turn
//! touches (a queue's reserve, head, count and budget; pending, stop, the FIFO sequence, the
//! idle count) sit 32 words (a 128-byte L2 line) apart, so that the probes' loads do not queue
//! the claims' atomics behind them (the shader's layout comment has the measurement).
#![allow(dead_code)] // the whole host twin of the layout: not every word is read by the host

pub const QSTRIDE: usize = 128;
pub const Q_RESERVE: usize = 0;
pub const Q_HEAD: usize = 32;
pub const Q_COUNT: usize = 64;
pub const Q_BUDGET: usize = 96;
pub const Q_PEAK: usize = 97;
pub const Q_EXECUTED: usize = 98;
pub const Q_BATCHES: usize = 99;
pub const Q_BLOCKED: usize = 100;
/// Largest worst-case output to this queue of a batch refused for lack of room (in any queue).
pub const Q_DEMAND: usize = 101;
/// Items the device compaction kept in this queue (written only by `megakernel_compact.wgsl`).
pub const Q_KEPT: usize = 102;
/// Items run from the workgroups' local queues (never ticketed in this queue).
pub const Q_LOCAL: usize = 103;

pub const G_PENDING: usize = 0;
pub const G_STOP: usize = 32;
pub const G_ERROR: usize = 33;
pub const G_ERR_A: usize = 34;
pub const G_ERR_B: usize = 35;
pub const G_IDLE: usize = 36;
pub const G_SEQ: usize = 64;
pub const G_ABANDONED: usize = 37;
pub const G_PROBE_STARTED: usize = 38;
pub const G_PROBE_FINISHED: usize = 39;
pub const G_PROBE_RESIDENT: usize = 40;
pub const G_ITER_EXITS: usize = 41;
/// Slots the device compaction found reserved but unpublished, or could not place.
pub const G_LOST: usize = 42;
/// Workgroups idle right now (local queues only).
pub const G_IDLE_NOW: usize = 96;
/// First of the turn anatomy's counters (`anatomy::TurnAnatomy`, `AN_*` in the shader).
pub const G_AN: usize = 128;
pub const AN_WORDS: usize = 8;
pub const GLOBAL_WORDS: usize = G_AN + AN_WORDS;

pub const ERR_EMIT: u32 = 1;

pub const P_MAX_ITERS: usize = 0;
pub const P_SPIN: usize = 1;
pub const P_PROBE: usize = 2;
pub const P_POLICY: usize = 3;
pub const P_OUTBOX_STRIDE: usize = 4;
/// Always 0: the idle pause loads it through its own last value, a chain of dependent loads.
pub const P_PAUSE_LINK: usize = 5;
pub const P_IDLE_BACKOFF: usize = 6;
/// First word of the workgroups' local areas in the slots buffer (past every queue's slots).
pub const P_LOCAL_BASE: usize = 7;
pub const P_QUEUES: usize = 8;

pub const MAX_BATCH: u32 = 1024;
pub const EMPTY: u32 = 0;
pub const CONSUMED: u32 = u32::MAX;
/// Stamp of items uploaded by the host (device stamps start at 2).
pub const SEED_STAMP: u32 = 1;

pub fn ctrl_words(nq: usize) -> usize {
    nq * QSTRIDE + GLOBAL_WORDS
}

pub fn g(nq: usize, i: usize) -> usize {
    nq * QSTRIDE + i
}

pub fn q(queue: usize, i: usize) -> usize {
    queue * QSTRIDE + i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl::wgsl_const;

    #[test]
    fn hot_words_have_lines_of_their_own() {
        const LINE: usize = 32; // 128 bytes
        let lines = |words: &[usize]| {
            let mut l: Vec<usize> = words.iter().map(|w| w / LINE).collect();
            l.sort();
            l.dedup();
            l.len() == words.len()
        };
        assert!(lines(&[Q_RESERVE, Q_HEAD, Q_COUNT, Q_BUDGET]));
        assert!(lines(&[G_PENDING, G_STOP, G_SEQ, G_IDLE_NOW, G_AN]));
        // Queue blocks and the global block start on a line, for any queue count.
        assert_eq!(QSTRIDE % LINE, 0);
        assert!([Q_LOCAL, Q_KEPT, Q_DEMAND].iter().all(|&w| w < QSTRIDE));
    }

    #[test]
    fn ctrl_words_match_the_shader() {
        let src = super::super::wgsl::TEMPLATE;
        for (name, host) in [
            ("QSTRIDE", QSTRIDE),
            ("Q_RESERVE", Q_RESERVE),
            ("Q_HEAD", Q_HEAD),
            ("Q_COUNT", Q_COUNT),
            ("Q_BUDGET", Q_BUDGET),
            ("Q_PEAK", Q_PEAK),
            ("Q_EXECUTED", Q_EXECUTED),
            ("Q_BATCHES", Q_BATCHES),
            ("Q_BLOCKED", Q_BLOCKED),
            ("Q_DEMAND", Q_DEMAND),
            ("Q_LOCAL", Q_LOCAL),
            ("G_IDLE_NOW", G_IDLE_NOW),
            ("G_PENDING", G_PENDING),
            ("G_STOP", G_STOP),
            ("G_ERROR", G_ERROR),
            ("G_ERR_A", G_ERR_A),
            ("G_ERR_B", G_ERR_B),
            ("G_IDLE", G_IDLE),
            ("G_SEQ", G_SEQ),
            ("G_PROBE_STARTED", G_PROBE_STARTED),
            ("G_PROBE_FINISHED", G_PROBE_FINISHED),
            ("G_ABANDONED", G_ABANDONED),
            ("G_PROBE_RESIDENT", G_PROBE_RESIDENT),
            ("G_ITER_EXITS", G_ITER_EXITS),
            ("G_AN", G_AN),
            ("AN_WORDS", AN_WORDS),
            ("P_MAX_ITERS", P_MAX_ITERS),
            ("P_PAUSE_LINK", P_PAUSE_LINK),
            ("P_IDLE_BACKOFF", P_IDLE_BACKOFF),
        ] {
            assert_eq!(wgsl_const(src, name), Some(host), "{name}");
        }
        // Words the compaction kernel writes are unused by the megakernel and inside ctrl.
        const { assert!(Q_KEPT > Q_DEMAND && Q_KEPT < QSTRIDE) };
        const { assert!(G_LOST > G_ITER_EXITS && G_LOST < GLOBAL_WORDS) };
    }
}
