//! `raypipe museum-art`: the BART museum's animated art at any size, as the
//! `animartN.aff` that museumN.aff includes ([`crate::input::generate::museum_art`]).

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;

use crate::input::generate::museum_art::{museum_art, MAX_LEVEL};
use crate::output;

/// `raypipe museum-art`.
#[derive(Args, Debug)]
pub struct MuseumArtArgs {
    /// 4^LEVEL animated triangles: 5 is BART's museum5, 6–8 its larger variants.
    #[arg(long, value_name = "LEVEL")]
    pub level: u32,
    /// The random positions' seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The AFF file to write (e.g. animart6.aff beside museum5.aff).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
}

pub(crate) fn cmd_museum_art(a: MuseumArtArgs) -> Result<()> {
    if !(1..=MAX_LEVEL).contains(&a.level) {
        bail!("--level {} must be 1 to {MAX_LEVEL}", a.level);
    }
    let text = museum_art(a.level, a.seed);
    output::write_bytes(&a.output, text.as_bytes())?;
    println!("wrote {} ({} animated triangles)", a.output.display(), 4u64.pow(a.level));
    Ok(())
}
