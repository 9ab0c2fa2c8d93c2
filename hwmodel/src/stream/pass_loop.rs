//! The multipass architecture's loop (Purcell 2002 §3.2, §4.1) over one screen of rays:
//! an eye-ray pass (first wave only), a traversal-setup pass, then traversal and
//! intersection passes as the oracle picks them until no ray waits for either; the
//! shading pass follows ([`crate::stream::shading_pass`]).
//!
//! Every pass reads the stencil of every fragment it covers; only the fragments whose
//! stencil matches the pass run its kernel, `N` (or `M`) iterations of it when unrolled.
//! A ray that leaves the kernel's stage mid-pass idles through the remaining
//! iterations — they cost instructions, and memory references too unless suppressed.
//! Each processed ray reads its state words once and writes them once per pass.

use raypipe_core::{Intersector, NoProbe, Ray};

use crate::stream::cost_model::Kernel;
use crate::stream::counters::{PassKind, PassRecord, RayWork};
use crate::stream::frame::StreamMachine;
use crate::stream::memory_probe::StreamProbe;
use crate::stream::oracle::{LoopPass, Waiting};
use crate::stream::ray_state::StreamRay;
use crate::stream::stencil::{RayStage, Stencil};

/// State textures live in their own address space, above any scene image: one
/// screen-sized RGBA texture per texel of state ([`crate::stream::ray_state::words`]),
/// fragment `i`'s texel at `16 i`, so that a 48-byte cache line holds three neighbours'
/// texels — the locality a texture cache sees in Purcell's state textures.
const STATE_BASE: u64 = 1 << 40;
/// The state textures: the ray's two texels, the DDA's two (the list position in the
/// second), the hit.
const RAY_TEXELS: [u64; 2] = [0, 1];
const DDA_TEXELS: [u64; 2] = [2, 3];
const HIT_TEXEL: u64 = 4;

/// The texels a loop kernel reads and writes.
fn state_texels(k: Kernel) -> (&'static [u64], &'static [u64]) {
    match k {
        Kernel::Setup => (&RAY_TEXELS, &[2, 3, HIT_TEXEL]),
        Kernel::Traverse => (&[0, 1, 2, 3, HIT_TEXEL], &DDA_TEXELS),
        Kernel::Intersect => (&[0, 1, 2, 3, HIT_TEXEL], &[3, HIT_TEXEL]),
        _ => (&[], &[]),
    }
}

/// Versions of the state textures: a pass that writes a texture makes a new version
/// (at a new address), so the cache never serves a texel the pass before overwrote —
/// the invalidation a render-to-texture pass needs.
#[derive(Clone, Debug, Default)]
pub(crate) struct StateTextures {
    versions: [u64; 5],
}

impl StateTextures {
    /// The byte address of fragment `i`'s texel of texture `t`.
    fn addr(&self, t: u64, i: usize) -> u64 {
        STATE_BASE + (((t << 20) | (self.versions[t as usize] & 0xF_FFFF)) << 28) + i as u64 * 16
    }

    /// Reads fragment `i`'s texels for kernel `k` through the probe.
    fn read(&self, k: Kernel, i: usize, probe: &mut StreamProbe<'_>) {
        for &t in state_texels(k).0 {
            probe.state_read(self.addr(t, i), 4);
        }
    }

    /// Kernel `k`'s pass is over: what it wrote is a new version.
    fn wrote(&mut self, k: Kernel) {
        for &t in state_texels(k).1 {
            self.versions[t as usize] += 1;
        }
    }
}

/// A ray's current runs of traversal steps and intersections, to count the passes it
/// needs at least ([`RayWork`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Runs {
    traverse: u64,
    intersect: u64,
}

impl Runs {
    /// Notes one useful iteration of the kernel for `stage`.
    pub(crate) fn step(&mut self, stage: RayStage, work: &mut RayWork) {
        match stage {
            RayStage::Traverse => {
                self.traverse += 1;
                work.steps += 1;
            }
            RayStage::Intersect => {
                self.intersect += 1;
                work.intersections += 1;
            }
            _ => {}
        }
    }

    /// The ray left `from`: closes the run (rounded up to whole passes of `per_pass`).
    pub(crate) fn close(&mut self, from: RayStage, per_pass: (u32, u32), work: &mut RayWork) {
        match from {
            RayStage::Traverse if self.traverse > 0 => {
                work.traverse_passes += self.traverse.div_ceil(per_pass.0 as u64);
                self.traverse = 0;
            }
            RayStage::Intersect if self.intersect > 0 => {
                work.intersect_passes += self.intersect.div_ceil(per_pass.1 as u64);
                self.intersect = 0;
            }
            _ => {}
        }
    }
}

impl<I: Intersector> StreamMachine<'_, I> {
    /// The passes the ray still needs of each kind, from running a copy of it to the
    /// end (what the clairvoyant oracle knows).
    fn future(&self, ray: &StreamRay<I>) -> (u64, u64) {
        let per_pass = (self.cfg.unroll.traverse, self.cfg.unroll.intersect);
        let (mut r, mut work, mut runs) = (*ray, RayWork::default(), Runs::default());
        while let Some(before) = r.run_kernel(&self.scene, &self.grid, &mut NoProbe) {
            runs.step(before, &mut work);
            if r.stage != before {
                runs.close(before, per_pass, &mut work);
            }
        }
        (work.traverse_passes, work.intersect_passes)
    }

    /// Runs one screen of rays (`(ray, any-hit)` per fragment) to the end of traversal.
    pub(crate) fn multipass_screen(
        &mut self,
        wave: u32,
        screen: u32,
        rays: &[Option<(Ray, bool)>],
        generate: bool,
    ) -> Result<Vec<Option<StreamRay<I>>>, String> {
        let (width, _) = self.screen();
        let n = rays.len();
        let mut stencil = Stencil::new(n, width);
        let covered = stencil.covered();
        let new_pass =
            |kind, iterations| PassRecord { wave, screen, kind: Some(kind), iterations, covered, ..Default::default() };
        if generate {
            self.generate_pass(new_pass(PassKind::Generate, 1), rays, &mut stencil, covered);
        }
        let (mut state, mut alive) = self.setup_pass(new_pass(PassKind::Setup, 1), rays, &mut stencil);

        let per_pass = (self.cfg.unroll.traverse, self.cfg.unroll.intersect);
        let mut work = vec![RayWork::default(); n];
        let mut runs = vec![Runs::default(); n];
        let mut future: Vec<(u64, u64)> = Vec::new();
        if self.cfg.oracle.needs_future() {
            future = state.iter().map(|s| s.as_ref().map_or((0, 0), |r| self.future(r))).collect();
        }
        let mut last: Option<LoopPass> = None;
        let mut idle_passes = 0;
        while !alive.is_empty() {
            let kind = self.cfg.oracle.next(&waiting(&alive, &state, &future), last);
            last = Some(kind);
            let (kernel, iterations, stage, pass_kind) = match kind {
                LoopPass::Traverse => (Kernel::Traverse, per_pass.0, RayStage::Traverse, PassKind::Traverse),
                LoopPass::Intersect => (Kernel::Intersect, per_pass.1, RayStage::Intersect, PassKind::Intersect),
            };
            let mut p = new_pass(pass_kind, iterations);
            stencil.test_pass();
            let (cache_state, suppress) = (self.cfg.cache_state, self.cfg.suppress);
            let textures = std::mem::take(&mut self.state_textures);
            let mut probe = StreamProbe::new(&mut self.cache, iterations > 1 && !suppress);
            for &i in &alive {
                let Some(ray) = state[i].as_mut() else { continue };
                if ray.stage != stage {
                    continue;
                }
                p.processed += 1;
                if cache_state {
                    textures.read(kernel, i, &mut probe);
                }
                for it in 0..iterations {
                    if ray.stage == stage {
                        probe.begin();
                        if it == 0 {
                            // Later iterations have the entry in a register.
                            ray.reread_entry(&self.grid, &mut probe);
                        }
                        ray.run_kernel(&self.scene, &self.grid, &mut probe);
                        p.useful += 1;
                        runs[i].step(stage, &mut work[i]);
                    } else {
                        p.idle += 1;
                        if !suppress {
                            probe.replay();
                        }
                    }
                }
                if ray.stage != stage {
                    runs[i].close(stage, per_pass, &mut work[i]);
                    stencil.set(i, ray.stage);
                }
                if let Some(f) = future.get_mut(i) {
                    match kind {
                        LoopPass::Traverse => f.0 = f.0.saturating_sub(1),
                        LoopPass::Intersect => f.1 = f.1.saturating_sub(1),
                    }
                }
            }
            let words = probe.take_words();
            drop(probe);
            self.state_textures = textures;
            self.state_textures.wrote(kernel);
            p.stencil = stencil.take_counts();
            let (executions, processed) = (p.useful + p.idle, p.processed);
            self.charge(kernel, executions, processed, words, &mut p);
            alive.retain(|&i| state[i].is_some_and(|s| s.stage != RayStage::Done));
            p.active_after = alive.len() as u64;
            match kind {
                LoopPass::Traverse => self.loops.traverse_passes += 1,
                LoopPass::Intersect => self.loops.intersect_passes += 1,
            }
            idle_passes = if p.useful == 0 { idle_passes + 1 } else { 0 };
            self.passes.push(p);
            if idle_passes > 2 {
                return Err("internal error: the pass loop makes no progress".into());
            }
        }
        self.close_screen(&work);
        Ok(state)
    }

    /// The eye-ray pass: every fragment runs the eye-ray kernel, which writes the stencil
    /// of the rays that hit the scene box (`covered` fragments).
    fn generate_pass(&mut self, mut p: PassRecord, rays: &[Option<(Ray, bool)>], stencil: &mut Stencil, covered: u64) {
        (p.processed, p.useful) = (covered, covered);
        for (i, r) in rays.iter().enumerate() {
            if r.is_some() {
                stencil.set(i, RayStage::Traverse);
            }
        }
        p.stencil = stencil.take_counts();
        self.charge(Kernel::Generate, covered, covered, [0; 4], &mut p);
        self.passes.push(p);
    }

    /// The traversal setup pass: each ray's state and the stencil of its stage; returns
    /// the states and the rays still to trace.
    fn setup_pass(
        &mut self,
        mut p: PassRecord,
        rays: &[Option<(Ray, bool)>],
        stencil: &mut Stencil,
    ) -> (Vec<Option<StreamRay<I>>>, Vec<usize>) {
        stencil.test_pass();
        let mut state: Vec<Option<StreamRay<I>>> = Vec::with_capacity(rays.len());
        let textures = std::mem::take(&mut self.state_textures);
        let mut probe = StreamProbe::new(&mut self.cache, false);
        for (i, r) in rays.iter().enumerate() {
            if r.is_some() && self.cfg.cache_state {
                textures.read(Kernel::Setup, i, &mut probe);
            }
            state.push(r.map(|(ray, any_hit)| {
                let s = StreamRay::<I>::setup(&self.grid, ray, any_hit);
                stencil.set(i, s.stage);
                s
            }));
        }
        drop(probe);
        self.state_textures = textures;
        self.state_textures.wrote(Kernel::Setup);
        p.processed = state.iter().flatten().count() as u64;
        p.useful = p.processed;
        p.stencil = stencil.take_counts();
        let processed = p.processed;
        self.charge(Kernel::Setup, processed, processed, [0; 4], &mut p);
        let alive: Vec<usize> =
            (0..rays.len()).filter(|&i| state[i].is_some_and(|s| s.stage != RayStage::Done)).collect();
        p.active_after = alive.len() as u64;
        // Twelve words to write: the paper's setup takes two passes (§3.1.2), and so
        // does this one.
        let repeats = self.output_repeats(Kernel::Setup, &p, self.costs.get(Kernel::Setup).w);
        self.passes.push(p);
        self.passes.extend(repeats);
        (state, alive)
    }

    /// A screen's loop is over: every ray's work is noted, and the optimal bound (the
    /// most traversal plus the most intersection passes any ray needed) added.
    fn close_screen(&mut self, work: &[RayWork]) {
        let (mut max_t, mut max_i) = (0, 0);
        for w in work {
            max_t = max_t.max(w.traverse_passes);
            max_i = max_i.max(w.intersect_passes);
            self.note_work(w);
        }
        self.loops.bound += max_t + max_i;
        self.loops.loops += 1;
    }
}

/// What the oracle sees before a pass: how many live rays wait to traverse and to
/// intersect, and (for the optimal oracle, which knows each ray's future) the bound on
/// the passes left after either choice.
fn waiting<I: Intersector>(alive: &[usize], state: &[Option<StreamRay<I>>], future: &[(u64, u64)]) -> Waiting {
    let mut w = Waiting::default();
    for &i in alive {
        match state[i].map(|s| s.stage) {
            Some(RayStage::Traverse) => w.traverse += 1,
            Some(RayStage::Intersect) => w.intersect += 1,
            _ => {}
        }
    }
    if !future.is_empty() {
        w.bound_after = Some(bounds_after(alive, state, future));
    }
    w
}

/// The lower bound on the passes left after a traversal pass and after an intersection
/// pass: the largest remaining traversal passes plus the largest remaining
/// intersection passes, with the waiting rays' next pass taken off.
fn bounds_after<I: Intersector>(alive: &[usize], state: &[Option<StreamRay<I>>], future: &[(u64, u64)]) -> (u64, u64) {
    let (mut t, mut i, mut t_after_t, mut i_after_i) = (0, 0, 0, 0);
    for &k in alive {
        let (ft, fi) = future[k];
        let stage = state[k].map(|s| s.stage);
        t = t.max(ft);
        i = i.max(fi);
        t_after_t = t_after_t.max(if stage == Some(RayStage::Traverse) { ft.saturating_sub(1) } else { ft });
        i_after_i = i_after_i.max(if stage == Some(RayStage::Intersect) { fi.saturating_sub(1) } else { fi });
    }
    (t_after_t + i, t + i_after_i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_texels_share_lines_with_neighbours_and_never_outlive_a_write() {
        let mut t = StateTextures::default();
        // Three neighbours' 16-byte texels in one 48-byte line; textures apart.
        assert_eq!(t.addr(2, 3) / 48, t.addr(2, 5) / 48);
        assert_ne!(t.addr(2, 5) / 48, t.addr(2, 6) / 48);
        assert_ne!(t.addr(1, 0) / 48, t.addr(2, 0) / 48);
        // Traversal writes the DDA's texels: new addresses for them only.
        let (dda, ray) = (t.addr(2, 7), t.addr(0, 7));
        t.wrote(Kernel::Traverse);
        assert_ne!(t.addr(2, 7), dda);
        assert_eq!(t.addr(0, 7), ray);
    }
}
