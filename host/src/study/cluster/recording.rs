//! What a distributed run records for the cluster model: the run (its ranks, image,
//! tiles, the frames' measured times and, for a bricked scene, every brick's sizes),
//! then every tile a worker rendered — how long it took, how long of that its rays
//! waited for bricks, the bytes of its message and the bricks it needed. One JSON object
//! per line, the run first.

use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};

/// The most tiles a recording may hold (a thousand frames of 1024 × 1024 in 32-pixel tiles).
pub const MAX_TILES: usize = 1 << 20;

/// The run a recording comes from.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunRecord {
    /// Ranks, hosts and MPI library, as the report gives them.
    pub identity: String,
    /// Worker ranks.
    pub workers: u32,
    /// Hardware threads of the master's host (the machine the tile times were measured on).
    pub host_threads: u32,
    /// Hosts the ranks ran on.
    pub hosts: u32,
    /// Image width and height, in pixels.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Side of a tile, in pixels.
    pub tile: u32,
    /// Tiles a worker held at once.
    pub in_flight: u32,
    /// Tiles a worker rendered side by side.
    pub batch: u32,
    /// Each frame's measured seconds, master's clock.
    pub frame_seconds: Vec<f64>,
    /// The master's seconds per tile received (decoding, placing, answering), measured.
    pub master_seconds_per_tile: f64,
    /// A bricked scene's bricks: stored and decompressed bytes, by brick number.
    pub bricks: Vec<(u64, u64)>,
}

/// One rendered tile.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TileRecord {
    /// Frame of the walk.
    pub frame: u32,
    /// Tile number in the frame.
    pub tile: u32,
    /// The worker rank that rendered it.
    pub rank: u32,
    /// Seconds the worker spent on it.
    pub seconds: f64,
    /// Of them, seconds its rays all waited for bricks.
    pub waited: f64,
    /// Bytes of its message to the master.
    pub bytes: u64,
    /// The bricks its rays needed.
    pub bricks: Vec<u32>,
}

/// A whole recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The run.
    pub run: RunRecord,
    /// Its tiles, in the order they arrived.
    pub tiles: Vec<TileRecord>,
}

impl Recording {
    /// Writes it as JSON lines (to a temporary file renamed into place).
    pub fn write(&self, path: &Path) -> Result<()> {
        crate::output::write_atomic(path, |w| {
            writeln!(w, "{}", serde_json::to_string(&self.run)?)?;
            for t in &self.tiles {
                writeln!(w, "{}", serde_json::to_string(t)?)?;
            }
            Ok(())
        })
    }

    /// Reads and checks one; every problem is an error naming the file and the line.
    pub fn read(path: &Path) -> Result<Recording> {
        let mut file = crate::input::read_file::open_regular(path)?.0;
        let mut text = String::new();
        std::io::Read::read_to_string(&mut file, &mut text)
            .with_context(|| format!("{}: cannot read as text", path.display()))?;
        Recording::parse(&text, &path.display().to_string())
    }

    /// A recording from its text; `name` names it in errors.
    pub fn parse(text: &str, name: &str) -> Result<Recording> {
        let mut lines = text.lines();
        let first = lines.next().ok_or_else(|| anyhow!("{name}: empty: not a recording"))?;
        let run: RunRecord = serde_json::from_str(first).map_err(|e| anyhow!("{name}:1: not a run record: {e}"))?;
        let mut tiles = Vec::new();
        for (k, line) in lines.enumerate() {
            let t: TileRecord =
                serde_json::from_str(line).map_err(|e| anyhow!("{name}:{}: not a tile record: {e}", k + 2))?;
            tiles.push(t);
            if tiles.len() > MAX_TILES {
                bail!("{name}: more than {MAX_TILES} tiles");
            }
        }
        let rec = Recording { run, tiles };
        rec.check().map_err(|e| anyhow!("{name}: {e}"))?;
        Ok(rec)
    }

    /// Every frame's tiles, by tile number (a checked recording has each once).
    pub fn by_frame(&self) -> Vec<Vec<&TileRecord>> {
        let per_frame = self.tiles_per_frame() as usize;
        let mut frames: Vec<Vec<Option<&TileRecord>>> = vec![vec![None; per_frame]; self.frames() as usize];
        for t in &self.tiles {
            if let Some(slot) = frames.get_mut(t.frame as usize).and_then(|f| f.get_mut(t.tile as usize)) {
                *slot = Some(t);
            }
        }
        frames.into_iter().map(|f| f.into_iter().flatten().collect()).collect()
    }

    /// Frames recorded.
    pub fn frames(&self) -> u32 {
        self.run.frame_seconds.len() as u32
    }

    /// Tiles in a frame.
    pub fn tiles_per_frame(&self) -> u32 {
        self.run.width.div_ceil(self.run.tile.max(1)) * self.run.height.div_ceil(self.run.tile.max(1))
    }

    fn check(&self) -> Result<()> {
        let r = &self.run;
        if r.workers == 0 || r.tile == 0 || r.width == 0 || r.height == 0 || r.frame_seconds.is_empty() {
            bail!("a run of no workers, tiles or frames");
        }
        if r.width > 65536 || r.height > 65536 || r.frame_seconds.len() > MAX_TILES || r.bricks.len() > 1 << 24 {
            bail!("an image, walk or scene larger than any run makes");
        }
        if self.tiles_per_frame() as usize * r.frame_seconds.len() != self.tiles.len() {
            bail!("{} tiles, not {} frames of {}", self.tiles.len(), r.frame_seconds.len(), self.tiles_per_frame());
        }
        let finite = |v: f64| v.is_finite() && v >= 0.0;
        if !r.frame_seconds.iter().all(|&s| finite(s)) || !finite(r.master_seconds_per_tile) {
            bail!("a time that is negative or not a number");
        }
        let per_frame = self.tiles_per_frame() as usize;
        let mut seen = vec![false; self.tiles.len()];
        for t in &self.tiles {
            let k = t.frame;
            if k >= self.frames() || t.tile as usize >= per_frame {
                bail!("frame {k}: tile {} is out of the walk or the image", t.tile);
            }
            if std::mem::replace(&mut seen[k as usize * per_frame + t.tile as usize], true) {
                bail!("frame {k}: tile {} twice", t.tile);
            }
            if !finite(t.seconds) || !finite(t.waited) || t.waited > t.seconds {
                bail!(
                    "frame {k}: tile {}: a time that is negative, not a number, or a wait longer than the tile",
                    t.tile
                );
            }
            if let Some(&b) = t.bricks.iter().find(|&&b| b as usize >= r.bricks.len()) {
                bail!("frame {k}: tile {}: brick {b} is not in the scene", t.tile);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RUN: &str = r#"{"identity":"t","workers":1,"host_threads":2,"hosts":1,"width":16,"height":16,"tile":16,"in_flight":4,"batch":2,"frame_seconds":[0.5],"master_seconds_per_tile":0.0,"bricks":[[10,20]]}"#;

    #[test]
    fn recordings_round_trip_and_bad_ones_are_one_line_errors() {
        let tile = r#"{"frame":0,"tile":0,"rank":1,"seconds":0.5,"waited":0.1,"bytes":3100,"bricks":[0]}"#;
        let rec = Recording::parse(&format!("{RUN}\n{tile}\n"), "r").unwrap();
        assert_eq!(rec.by_frame()[0][0].bricks, [0]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.jsonl");
        rec.write(&path).unwrap();
        assert_eq!(Recording::read(&path).unwrap(), rec);
        let bad = [
            String::new(),
            "{}".to_string(),
            RUN.to_string(),
            format!("{RUN}\n{tile}\n{tile}"),
            format!("{RUN}\n{}", tile.replace(r#""bricks":[0]"#, r#""bricks":[1]"#)),
            format!("{RUN}\n{}", tile.replace("0.1", "0.9")),
            format!("{RUN}\n{}", tile.replace(r#""tile":0"#, r#""tile":1"#)),
            format!("{RUN}\nnot json"),
        ];
        for text in bad {
            let e = Recording::parse(&text, "r").unwrap_err();
            assert!(!format!("{e:#}").contains('\n') && format!("{e:#}").starts_with("r"), "{e:#}");
        }
    }
}
