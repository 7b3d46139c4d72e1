//! Writes the stacked scene of occlusion culling (`reyes::scene::stacked`) as RIB:
//!
//! ```sh
//! cargo run --release -p reyes --example stacked_rib -- 256 4 1920 1080 > stacked.rib
//! reyes render stacked.rib --gpu --stats on.json
//! reyes render stacked.rib --gpu --occlusion off --stats off.json
//! ```
//!
//! Arguments: layers (default 256), patches per layer side (4), width (1920), height (1080).

fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| {
            a.parse().unwrap_or_else(|_| {
                eprintln!(
                    "usage: stacked_rib [LAYERS [PER_SIDE [WIDTH [HEIGHT]]]]: {a:?} is not a number"
                );
                std::process::exit(2)
            })
        })
        .collect();
    let arg = |k: usize, d: u32| args.get(k).copied().unwrap_or(d);
    print!(
        "{}",
        reyes::scene::stacked::stacked_rib(arg(0, 256), arg(1, 4), arg(2, 1920), arg(3, 1080))
    );
}
