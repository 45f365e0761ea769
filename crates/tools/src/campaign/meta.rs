//! `campaign.json`, a campaign folder's identity: written when a campaign starts, read to
//! resume, merge and finish it. Apart from `files.rs` so that the plots (which `files.rs`
//! writes, and which read the histograms' columns here) do not import the folder's code.

use super::{CAMPAIGN_JSON, CampaignError, Shard};
use std::path::Path;

/// A campaign folder's identity: what `campaign.json` holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Meta {
    /// The scene file, as given.
    pub scene: String,
    /// Runs in the whole campaign.
    pub runs: u64,
    /// Master seed.
    pub seed: u64,
    /// The shard this folder holds (`0/1` for a whole or merged campaign).
    pub shard: Shard,
    /// The stat columns drawn as histograms.
    pub histograms: Vec<String>,
    /// [`super::Campaign::scene_digest`] of the scene the runs were made with (`None` in a
    /// folder written before it was recorded).
    pub scene_digest: Option<String>,
    /// The flight software that stepped the runs (`satsim.campaign(controller=...)`: its
    /// factory, period and metrics, as [`super::stepped::Stepped::identity`] writes them);
    /// `None` for the built-in controllers (`satsim campaign`). A folder is resumed and
    /// merged only with the same.
    pub controller: Option<String>,
}

impl Meta {
    /// How many runs this folder should hold.
    pub fn expected(&self) -> u64 {
        (0..self.runs).filter(|k| self.shard.contains(*k)).count() as u64
    }

    /// The flight software, as messages name it: `` `its identity` ``, or "the built-in
    /// controllers".
    pub fn controller_name(&self) -> String {
        self.controller
            .as_deref()
            .map_or("the built-in controllers".to_owned(), |c| format!("`{c}`"))
    }

    pub(crate) fn write(&self, dir: &Path) -> Result<(), CampaignError> {
        let mut v = serde_json::json!({
            "scene": self.scene,
            "runs": self.runs,
            "seed": self.seed,
            "shard": self.shard.to_string(),
            "histograms": self.histograms,
            "scene_digest": self.scene_digest,
        });
        if let Some(c) = &self.controller {
            v["controller"] = c.clone().into();
        }
        let path = dir.join(CAMPAIGN_JSON);
        let text = serde_json::to_string_pretty(&v).expect("JSON serialises") + "\n";
        std::fs::write(&path, text).map_err(|e| CampaignError::io(&path, e))
    }

    /// Reads `dir/campaign.json`.
    pub fn read(dir: &Path) -> Result<Meta, CampaignError> {
        let path = dir.join(CAMPAIGN_JSON);
        let text = std::fs::read_to_string(&path).map_err(|e| CampaignError::io(&path, e))?;
        let bad = |m: &str| CampaignError::io(&path, m);
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| CampaignError::io(&path, e))?;
        Ok(Meta {
            scene: v["scene"].as_str().ok_or_else(|| bad("no `scene`"))?.into(),
            runs: v["runs"].as_u64().ok_or_else(|| bad("no `runs`"))?,
            seed: v["seed"].as_u64().ok_or_else(|| bad("no `seed`"))?,
            shard: v["shard"]
                .as_str()
                .ok_or_else(|| bad("no `shard`"))?
                .parse()
                .map_err(|e: String| bad(&e))?,
            histograms: v["histograms"]
                .as_array()
                .ok_or_else(|| bad("no `histograms`"))?
                .iter()
                .map(|h| {
                    h.as_str()
                        .map(str::to_owned)
                        .ok_or_else(|| bad("bad `histograms`"))
                })
                .collect::<Result<_, _>>()?,
            scene_digest: v["scene_digest"].as_str().map(str::to_owned),
            controller: v["controller"].as_str().map(str::to_owned),
        })
    }
}
