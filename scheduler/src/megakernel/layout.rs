//! Host twin of the ctrl and params word layouts in `shaders/megakernel.wgsl`.
//! A test compiles the shader and checks each constant against these.

pub const QSTRIDE: usize = 16;
pub const Q_RESERVE: usize = 0;
pub const Q_HEAD: usize = 1;
pub const Q_COUNT: usize = 2;
pub const Q_BUDGET: usize = 3;
pub const Q_PEAK: usize = 4;
pub const Q_EXECUTED: usize = 5;
pub const Q_BATCHES: usize = 6;
pub const Q_BLOCKED: usize = 7;

pub const G_PENDING: usize = 0;
pub const G_STOP: usize = 1;
pub const G_ERROR: usize = 2;
pub const G_ERR_A: usize = 3;
pub const G_ERR_B: usize = 4;
pub const G_IDLE: usize = 5;
pub const G_SEQ: usize = 6;
pub const G_ABANDONED: usize = 7;
pub const G_PROBE_STARTED: usize = 8;
pub const G_PROBE_FINISHED: usize = 9;
pub const G_PROBE_RESIDENT: usize = 10;
pub const G_ITER_EXITS: usize = 11;
pub const GLOBAL_WORDS: usize = 16;

pub const ERR_EMIT: u32 = 1;

pub const P_MAX_ITERS: usize = 0;
pub const P_SPIN: usize = 1;
pub const P_PROBE: usize = 2;
pub const P_POLICY: usize = 3;
pub const P_OUTBOX_STRIDE: usize = 4;
pub const P_BATCH_STEPS: usize = 5;
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
