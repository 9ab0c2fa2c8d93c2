//! What an animation run measured, frame by frame (BART's rules: total time and
//! per-frame times, every frame in order): the update — bottom levels refitted or
//! rebuilt, the top level — and the render, their percentiles, and the trace rate.

use std::fmt::Write;

use crate::build::dynamic::CommitStats;
use crate::commands::animate::AnimateArgs;
use crate::input::aff::AffScene;

/// One frame's times.
#[derive(Clone, Copy, Debug)]
pub struct FrameTimes {
    /// Frame number.
    pub frame: u32,
    /// Its time in the animation.
    pub time: f64,
    /// What the commit did.
    pub update: CommitStats,
    /// Seconds posting, committing and validating the frame.
    pub update_secs: f64,
    /// Seconds rendering it.
    pub render_secs: f64,
    /// Rays traced.
    pub rays: u64,
}

/// The run's frames and what it was.
pub struct AnimationReport {
    header: Vec<String>,
    frames: Vec<FrameTimes>,
}

/// The `p`-th percentile of `v` (nearest rank).
pub fn percentile(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let k = ((p / 100.0) * s.len() as f64).ceil() as usize;
    s[k.clamp(1, s.len()) - 1]
}

impl AnimationReport {
    /// A report for `aff` rendered as `a` asks; loading and building took `load_secs`.
    pub fn new(aff: &AffScene, a: &AnimateArgs, load_secs: f64) -> AnimationReport {
        let s = &aff.scene;
        let stored: usize = s.bottoms.iter().map(|b| b.triangles.len()).sum();
        let drawn: usize = s.instances.iter().map(|i| s.bottoms[i.bottom as usize].triangles.len()).sum();
        let deforming: usize =
            s.bottoms.iter().zip(&aff.deforming).filter(|(_, d)| **d).map(|(b, _)| b.triangles.len()).sum();
        let (t0, t1, n) = aff.animation;
        let header = vec![
            format!("scene    {} ({n} frames, t = {t0} .. {t1})", s.name),
            format!(
                "geometry {drawn} triangles drawn ({stored} stored in {} meshes, {deforming} deforming), {} instances",
                s.bottoms.len(),
                s.instances.len()
            ),
            format!(
                "update   {} (auto threshold {}), algorithm {:?}, load and first build {load_secs:.3} s",
                a.updates.update.name(),
                a.updates.auto_threshold,
                a.algo.algo
            )
            .to_lowercase(),
        ];
        AnimationReport { header, frames: Vec::new() }
    }

    /// Adds a frame.
    pub fn add(&mut self, f: FrameTimes) {
        self.frames.push(f);
    }

    /// Every frame as CSV.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "frame,time,update_ms,refit_ms,rebuild_ms,top_ms,refits,rebuilds,cost_growth,render_ms,rays,mrays_per_s\n",
        );
        for f in &self.frames {
            let u = &f.update;
            let _ = writeln!(
                out,
                "{},{},{:.3},{:.3},{:.3},{:.3},{},{},{:.4},{:.3},{},{:.3}",
                f.frame,
                f.time,
                f.update_secs * 1e3,
                u.refit_seconds * 1e3,
                u.rebuild_seconds * 1e3,
                u.top_seconds * 1e3,
                u.refits,
                u.rebuilds,
                u.cost_growth,
                f.render_secs * 1e3,
                f.rays,
                f.rays as f64 / f.render_secs.max(1e-9) / 1e6
            );
        }
        out
    }

    /// The summary: totals, percentiles of update and render times, trace rates.
    pub fn lines(&self) -> Vec<String> {
        let mut out = self.header.clone();
        let n = self.frames.len();
        if n == 0 {
            return out;
        }
        let update: Vec<f64> = self.frames.iter().map(|f| f.update_secs * 1e3).collect();
        let render: Vec<f64> = self.frames.iter().map(|f| f.render_secs * 1e3).collect();
        let rate: Vec<f64> = self.frames.iter().map(|f| f.rays as f64 / f.render_secs.max(1e-9) / 1e6).collect();
        let total_update: f64 = update.iter().sum::<f64>() / 1e3;
        let total_render: f64 = render.iter().sum::<f64>() / 1e3;
        let rebuilds: u32 = self.frames.iter().map(|f| f.update.rebuilds).sum();
        let refits: u32 = self.frames.iter().map(|f| f.update.refits).sum();
        let pct = |v: &[f64]| {
            format!(
                "p50 {:.2}, p90 {:.2}, p99 {:.2}, max {:.2}",
                percentile(v, 50.0),
                percentile(v, 90.0),
                percentile(v, 99.0),
                percentile(v, 100.0)
            )
        };
        out.push(format!(
            "frames   {n}: total {:.3} s (update {total_update:.3} s, render {total_render:.3} s), {:.2} frames/s",
            total_update + total_render,
            n as f64 / (total_update + total_render).max(1e-9)
        ));
        out.push(format!("update   ms per frame: {} ({refits} refits, {rebuilds} rebuilds)", pct(&update)));
        out.push(format!("render   ms per frame: {}", pct(&render)));
        let (first, last) = (rate[0], rate[n - 1]);
        out.push(format!("trace    Mrays/s: {}; first frame {first:.2}, last frame {last:.2}", pct(&rate)));
        out
    }

    /// Prints the summary.
    pub fn print(&self) {
        for l in self.lines() {
            println!("{l}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::percentile;

    #[test]
    fn percentiles_are_nearest_ranks() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(percentile(&v, 50.0), 5.0);
        assert_eq!(percentile(&v, 90.0), 9.0);
        assert_eq!(percentile(&v, 100.0), 10.0);
        assert_eq!(percentile(&[3.0], 99.0), 3.0);
    }
}
