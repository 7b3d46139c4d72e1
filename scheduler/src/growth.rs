//! How a queue grows when its work does not fit: geometrically, so that a run started far too
//! small pays `O(log2(need / start))` growths, each followed by one relaunch (megakernel) or one
//! resumed round (multi-pass), instead of one relaunch per `start` items.

/// The capacity, in slots, of a queue of `capacity` slots that needs at least `need`: at least
/// double, straight to `need` when that is more, never past `limit` (and never smaller than
/// `capacity`). Doubling is the standard amortized growth of a dynamic array: the copies of all
/// growths together cost at most twice the final size, and `k` growths from `start` reach
/// `start × 2^k`.
pub fn grow(capacity: u32, need: u64, limit: u32) -> u32 {
    (capacity as u64 * 2)
        .max(need)
        .min(limit as u64)
        .max(capacity as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::grow;

    #[test]
    fn growth_doubles_jumps_to_the_need_and_stops_at_the_limit() {
        assert_eq!(grow(16, 0, 1 << 20), 32);
        assert_eq!(grow(16, 17, 1 << 20), 32);
        assert_eq!(grow(16, 1000, 1 << 20), 1000);
        assert_eq!(grow(16, 1000, 500), 500);
        assert_eq!(grow(600, 0, 500), 600);
        assert_eq!(grow(u32::MAX, 0, u32::MAX), u32::MAX);
    }
}
