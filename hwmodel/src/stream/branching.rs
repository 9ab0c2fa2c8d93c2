//! The branching architecture (Purcell 2002 §4.2) over one screen of rays: one pass in
//! which each fragment runs the fused program — eye ray, setup, then `while` not done:
//! `if` waiting to traverse, a step, `else` a triangle — with its state in registers:
//! no stencil, no state words between kernels. Its stream input and output are charged
//! as Table 1 charges them: a secondary ray's record read, colours and emitted records
//! written (the cost model's BR and BW).
//!
//! Fragments run in lock-step groups of `simd`: in each iteration a branch that any
//! ray of the group takes is executed by the whole group, so a group whose rays
//! disagree pays for both branches and its idle lanes count against its SIMD
//! efficiency. With `simd = 1` every fragment branches alone.

use raypipe_core::{Intersector, Ray};

use crate::stream::cost_model::Kernel;
use crate::stream::counters::{PassRecord, RayWork};
use crate::stream::frame::StreamMachine;
use crate::stream::memory_probe::StreamProbe;
use crate::stream::pass_loop::Runs;
use crate::stream::ray_state::StreamRay;
use crate::stream::stencil::{covered_fragments, RayStage};

impl<I: Intersector> StreamMachine<'_, I> {
    /// Runs one screen of rays to the end of traversal in one fused pass, counting into
    /// `fused`.
    pub(crate) fn branching_screen(
        &mut self,
        rays: &[Option<(Ray, bool)>],
        generate: bool,
        fused: &mut PassRecord,
    ) -> Vec<Option<StreamRay<I>>> {
        let n = rays.len();
        if generate {
            let (width, _) = self.screen();
            let fragments = covered_fragments(n, width);
            self.charge(Kernel::Generate, fragments, 0, [0; 4], fused);
        }
        let mut state: Vec<Option<StreamRay<I>>> =
            rays.iter().map(|r| r.map(|(ray, any_hit)| StreamRay::<I>::setup(&self.grid, ray, any_hit))).collect();
        let traced = state.iter().flatten().count() as u64;
        fused.processed += traced;
        // A secondary ray's record is the pass's stream input (eye rays are made in
        // registers).
        let inputs = if generate { 0 } else { traced };
        self.charge(Kernel::Setup, traced, inputs, [0; 4], fused);

        let simd = self.cfg.simd.max(1) as usize;
        let (mut exec, mut words) = ([0u64; 2], [[0u64; 4]; 2]);
        let mut work = vec![RayWork::default(); n];
        let mut runs = vec![Runs::default(); n];
        let mut probe = StreamProbe::new(&mut self.cache, false);
        for start in (0..n).step_by(simd) {
            let end = (start + simd).min(n);
            if simd == 1 {
                // Alone, a fragment pays only for the kernels it runs.
                let Some(ray) = state[start].as_mut() else { continue };
                while let Some(stage) = ray.run_kernel(&self.scene, &self.grid, &mut probe) {
                    let b = (stage == RayStage::Intersect) as usize;
                    exec[b] += 1;
                    fused.useful += 1;
                    runs[start].step(stage, &mut work[start]);
                    if ray.stage != stage {
                        runs[start].close(stage, (1, 1), &mut work[start]);
                    }
                    for (w, t) in words[b].iter_mut().zip(probe.take_words()) {
                        *w += t;
                    }
                }
                continue;
            }
            let width = state[start..end].iter().flatten().count() as u64;
            loop {
                let mut ran = false;
                for (b, stage) in [(0, RayStage::Traverse), (1, RayStage::Intersect)] {
                    let mut takers = 0u64;
                    for i in start..end {
                        let Some(ray) = state[i].as_mut() else { continue };
                        if ray.stage != stage {
                            continue;
                        }
                        takers += 1;
                        ray.run_kernel(&self.scene, &self.grid, &mut probe);
                        runs[i].step(stage, &mut work[i]);
                        if ray.stage != stage {
                            runs[i].close(stage, (1, 1), &mut work[i]);
                        }
                    }
                    if takers == 0 {
                        continue;
                    }
                    // The whole group executes a branch any of its rays takes.
                    ran = true;
                    exec[b] += width;
                    fused.useful += takers;
                    fused.idle += width - takers;
                    for (w, t) in words[b].iter_mut().zip(probe.take_words()) {
                        *w += t;
                    }
                }
                if !ran {
                    break;
                }
            }
        }
        drop(probe);
        self.charge(Kernel::Traverse, exec[0], 0, words[0], fused);
        self.charge(Kernel::Intersect, exec[1], 0, words[1], fused);
        for w in &work {
            self.note_work(w);
        }
        state
    }
}
