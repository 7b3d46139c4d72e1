//! A 32-bit integer hash with a WGSL twin, for workloads that derive pseudo-random values from
//! ids on both sides (the tree workload's shapes, Reyes's sample jitter) and must agree bit for
//! bit with their CPU reference.
//!
//! The function is Chris Wellons's `lowbias32` (found with his *hash-prospector*, 2018): two
//! xorshift-multiply rounds and a final xorshift, a bijection on `u32` with low bias. It is
//! not cryptographic.

/// `lowbias32(x)`: `x ^= x >> 16; x *= 0x7feb352d; x ^= x >> 15; x *= 0x846ca68b; x ^= x >> 16`
/// with wrapping multiplies. A bijection on `u32`; `lowbias32(0) == 0`.
pub fn lowbias32(x: u32) -> u32 {
    let mut h = x;
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    h
}

/// The WGSL twin of [`lowbias32`] as a function called `name`: `fn <name>(x: u32) -> u32`
/// (WGSL `u32` multiplication wraps, as the Rust one does).
pub fn lowbias32_wgsl(name: &str) -> String {
    format!(
        "fn {name}(x: u32) -> u32 {{\n    var h = x;\n    \
         h ^= h >> 16u; h *= 0x7feb352du; h ^= h >> 15u; h *= 0x846ca68bu; h ^= h >> 16u;\n    \
         return h;\n}}\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lowbias32_matches_an_independent_implementation_and_its_wgsl_twin_compiles() {
        // Expected values from an independent implementation (Python, 32-bit masked).
        assert_eq!(lowbias32(0), 0);
        assert_eq!(lowbias32(1), 0x6889_90c0);
        assert_eq!(lowbias32(2), 0xd113_2181);
        assert_eq!(lowbias32(0xdead_beef), 0xe628_c683);
        assert_eq!(lowbias32(u32::MAX), 0x6768_824a);
        let src = lowbias32_wgsl("h32") + "@compute @workgroup_size(1) fn main() { _ = h32(1u); }";
        crate::wgsl::validate("hash", &src).unwrap();
    }
}
