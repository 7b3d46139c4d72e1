//! Between two megakernel launches, when the first left work: the live items per queue, checked
//! against the pending count, and each queue's capacity for the next launch (docs/scheduler.md
//! 2.5, steps 5 and 6; the growth policy in section 6).

use super::ROOM_GROWTH;
use super::layout::{self, *};
use crate::error::RunError;
use crate::gpu::Gpu;
use crate::growth::grow;
use crate::stats::RunStats;

/// What [`size`] found after a launch that left work.
pub(super) struct Sizing {
    /// Tickets reserved per queue in the launch (seeds included).
    pub reserved: Vec<u32>,
    /// Live items per queue: reserved tickets that did not run.
    pub live: Vec<u32>,
    /// Whether a queue grew (`capacity` changed).
    pub grew: bool,
    /// A queue at its limit that should have grown: (queue, room it needed more than, blocked),
    /// a blocked queue named before one that is merely full.
    pub stuck: Option<(usize, u64, bool)>,
}

/// Reads the launch's counters `ctrl` (of `nq` queues), checks that the live items add up to
/// the pending and abandoned counts (else a `Device` error: a protocol violation, or on
/// lavapipe its loop cut), and grows `capacity` within `max_cap` where the next launch would
/// likely run out of room, counting each growth in `stats.queue_growths`.
pub(super) fn size(
    gpu: &Gpu,
    nq: usize,
    ctrl: &[u32],
    capacity: &mut [u32],
    max_cap: &[u32],
    stats: &mut RunStats,
) -> Result<Sizing, RunError> {
    // Live items per queue: every ticket reserved in this launch (seeds
    // included) that did not run; the executed ones are exactly the consumed slots.
    let reserved: Vec<u32> = (0..nq).map(|q| ctrl[layout::q(q, Q_RESERVE)]).collect();
    let live: Vec<u32> = (0..nq)
        .map(|q| reserved[q].saturating_sub(ctrl[layout::q(q, Q_EXECUTED)]))
        .collect();
    let expected = ctrl[g(nq, G_PENDING)] as u64 + ctrl[g(nq, G_ABANDONED)] as u64;
    if live.iter().map(|&n| n as u64).sum::<u64>() != expected {
        // On lavapipe the likely cause is known: its loop cut ended a body's loops.
        let hint = if gpu.is_lavapipe() {
            "; on lavapipe every loop of an invocation, the bodies' included, shares \
             one 65,535-iteration cut with the persistent loop, so a body with long \
             loops is cut short there (docs/scheduler.md, section 4): run it with a \
             multi-pass strategy on lavapipe, or with shorter loops"
        } else {
            ""
        };
        return Err(RunError::Device(format!(
            "queue accounting mismatch after a launch: {live:?} live by queue, \
             {expected} pending{hint}"
        )));
    }
    // A launch that ran out of room costs a relaunch: its queues grow fourfold.
    let out_of_room = (0..nq).any(|q| ctrl[layout::q(q, Q_BLOCKED)] != 0);
    let mut grew = false;
    // A queue at its limit that blocked a launch in which nothing ran; a blocked queue
    // is named before one that is merely full.
    let mut stuck: Option<(usize, u64, bool)> = None;
    for q in 0..nq {
        let n = live[q];
        let blocked = ctrl[layout::q(q, Q_BLOCKED)] != 0;
        // Capacity bounds the tickets of one launch (seeds included). A queue grows
        // before the next launch when it refused a batch for want of room, or when its
        // tickets, or its live items plus the worst-case output to it of the largest
        // refused batch (of any queue), passed half its capacity (the next launch, with
        // more room elsewhere, would likely run out): at least doubling
        // ([`ROOM_GROWTH`]-fold after a launch that ran out of room), straight to live +
        // that worst case when more.
        let demand = ctrl[layout::q(q, Q_DEMAND)] as u64;
        let half = capacity[q] as u64 / 2;
        if blocked || reserved[q] as u64 > half || n as u64 + demand > half {
            if capacity[q] >= max_cap[q] {
                // A blocked claim needed room beyond the whole capacity.
                let needed = if blocked {
                    capacity[q] as u64
                } else {
                    n as u64
                };
                if stuck.is_none_or(|s| blocked && !s.2) {
                    stuck = Some((q, needed, blocked));
                }
                continue;
            }
            let factor = if out_of_room { ROOM_GROWTH } else { 1 };
            let need = (n as u64 + demand).max(factor * capacity[q] as u64);
            capacity[q] = grow(capacity[q], need, max_cap[q]);
            stats.queue_growths += 1;
            grew = true;
        }
    }
    Ok(Sizing {
        reserved,
        live,
        grew,
        stuck,
    })
}
