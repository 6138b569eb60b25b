//! Culling strategies. Each decides which fine tiles the final pass draws:
//! - `None`: every tile (the reference image);
//! - `ThreePass`: GPU depth prepass of coarse proxies, exact visible-pixel count per tile, fine draw
//!   of tiles above a pixel threshold (all on the GPU in one submission; see `gpu`);
//! - `Oracle`: exactly the tiles with at least one visible pixel in the unculled image (a lower
//!   bound for benchmarks, not a practical method: it renders the reference first);
//! - `Horizon`: CPU horizon occlusion culling of height fields over a quadtree of their tiles,
//!   front to back with one horizon height per image column ([`horizon`]); meshes are not culled.

pub mod horizon;
#[cfg(test)]
pub(crate) mod reference;

use crate::error::{input_err, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Culling {
    None,
    ThreePass,
    Oracle,
    Horizon,
}

impl Culling {
    /// Every strategy, in the order Python lists them.
    pub const ALL: [Culling; 4] = [Self::None, Self::ThreePass, Self::Oracle, Self::Horizon];
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "none" => Ok(Self::None),
            "three_pass" => Ok(Self::ThreePass),
            "oracle" => Ok(Self::Oracle),
            "horizon" => Ok(Self::Horizon),
            _ => Err(input_err(
                "culling",
                format!("unknown culling {s:?}; expected one of \"none\", \"three_pass\", \"oracle\", \"horizon\""),
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::ThreePass => "three_pass",
            Self::Oracle => "oracle",
            Self::Horizon => "horizon",
        }
    }
}
