//! How to run a scenario, apart from what the scenario describes.

/// How candidates for onboard sensing are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NeighbourSearch {
    /// Uniform grid: O(N) per step.
    #[default]
    Grid,
    /// Every pair: O(N²), the reference for benchmarks.
    AllPairs,
}

/// Options of a run that are not part of the world it flies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunOptions {
    /// When false the followers' inputs are discarded: the method switched off, to show that
    /// the pass criterion can fail. Default true.
    pub adjustment_enabled: bool,
    /// How the sensors find candidates. Default: the grid.
    pub neighbour_search: NeighbourSearch,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self { adjustment_enabled: true, neighbour_search: NeighbourSearch::Grid }
    }
}
