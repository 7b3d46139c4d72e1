//! The suite's problem sizes ([`Scale`]): what every workload module sizes its cases by, so it
//! sits below both the workloads and the suite that runs them.

/// Problem sizes of the suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Scale {
    /// Sizes lavapipe on two cores runs in a couple of minutes (what the test runs).
    Small,
    /// Sizes for a real GPU: up to and past each workload's benchmark size.
    Full,
}

impl Scale {
    pub fn name(self) -> &'static str {
        match self {
            Scale::Small => "small",
            Scale::Full => "full",
        }
    }

    /// Timed runs per strategy and size when `--runs` is not given.
    pub fn default_runs(self) -> u32 {
        match self {
            Scale::Small => 2,
            Scale::Full => 10,
        }
    }
}
