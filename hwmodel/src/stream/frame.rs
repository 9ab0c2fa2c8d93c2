//! One frame on the stream machine: waves of rays (the eye rays, then each generation
//! of rays the shader emits), each laid out over screens of fragments, each screen run
//! by the configured architecture ([`crate::stream::pass_loop`],
//! [`crate::stream::branching`]) and shaded by core's shading kernels
//! ([`crate::stream::shading_pass`]). Pixels add their rays' radiance exactly
//! ([`RadianceSum`]), so the image is the host's whatever order rays end in.

use raypipe_core::camera::EyeRays;
use raypipe_core::image::GridView;
use raypipe_core::shade::color::rgb8;
use raypipe_core::shade::radiance_sum::RadianceSum;
use raypipe_core::shade::ray_record::RayRecord;
use raypipe_core::shade::shader::Shader;
use raypipe_core::{Hit, Intersector, Ray, SceneView, Vec3};

use crate::stream::config::{Architecture, StreamConfig};
use crate::stream::cost_model::{CostModel, Kernel};
use crate::stream::counters::{ByKernel, PassKind, PassRecord, RayWork};
use crate::stream::ray_state::StreamRay;
use crate::stream::report::{ratio, ClassRow, KernelRow, LoopTotals, StreamReport, Table2, Traffic};
use crate::stream::texture_cache::TextureCache;
use crate::stream::texture_cache::{CLASSES, CLASS_NAMES, STATE};

/// What a fragment of a screen holds: a ray to trace, or a primary hit that visibility
/// already decided (the shadow caster's G-buffer).
#[derive(Clone, Copy, Debug)]
pub enum Fragment {
    /// Nothing (the eye ray missed the scene box).
    Empty,
    /// A ray record to trace, then shade.
    Trace(RayRecord),
    /// A primary record whose hit is known.
    Visible(RayRecord, Option<Hit>),
}

/// The machine and everything it counts.
pub struct StreamMachine<'s, I: Intersector> {
    pub(crate) scene: SceneView<'s>,
    pub(crate) grid: GridView<'s>,
    pub(crate) eye: EyeRays,
    pub(crate) background: Vec3,
    pub(crate) shader: Option<Shader>,
    pub(crate) cfg: StreamConfig,
    pub(crate) costs: CostModel,
    pub(crate) cache: TextureCache,
    pub(crate) state_textures: crate::stream::pass_loop::StateTextures,
    visibility: Option<Vec<(Option<Ray>, Option<Hit>)>>,
    /// Every pass, in order.
    pub passes: Vec<PassRecord>,
    /// Totals by kernel.
    pub kernels: ByKernel,
    /// Loop totals (Table 2).
    pub loops: LoopTotals,
    /// Largest per-ray work.
    pub max_work: RayWork,
    /// Each pixel's linear radiance (shaders) or colour (ray casting).
    pub(crate) radiance: Vec<RadianceSum>,
    /// Ray casting's colour per pixel (one sample per pixel).
    pub(crate) framebuffer: Vec<Vec3>,
    /// Each pixel's primary hit (first sample).
    pub hits: Vec<Option<Hit>>,
    /// Rays traced by wave.
    pub rays_by_wave: Vec<u64>,
    _intersector: core::marker::PhantomData<I>,
}

/// Waves allowed before the machine gives up (a shader that never stops emitting).
const MAX_WAVES: usize = 256;

impl<'s, I: Intersector> StreamMachine<'s, I> {
    /// A machine for the view `eye` of `scene` (which must hold a uniform grid), shading
    /// with `shader` (`None`: ray casting).
    pub fn new(
        scene: SceneView<'s>,
        eye: EyeRays,
        background: Vec3,
        shader: Option<Shader>,
        cfg: &StreamConfig,
        costs: CostModel,
    ) -> Result<Self, String> {
        cfg.validate()?;
        let grid = *scene.grid().ok_or_else(|| {
            format!(
                "the scene image holds a {:?}; Purcell's stream machine walks a uniform grid (build it with --accel grid)",
                scene.accel()
            )
            .to_lowercase()
        })?;
        let pixels = (eye.width as usize) * (eye.height as usize);
        Ok(StreamMachine {
            scene,
            grid,
            eye,
            background,
            shader,
            cfg: cfg.clone(),
            costs,
            cache: TextureCache::new(&cfg.cache),
            state_textures: Default::default(),
            visibility: None,
            passes: Vec::new(),
            kernels: ByKernel::default(),
            loops: LoopTotals::default(),
            max_work: RayWork::default(),
            radiance: vec![RadianceSum::default(); pixels],
            framebuffer: vec![background; pixels],
            hits: vec![None; pixels],
            rays_by_wave: Vec::new(),
            _intersector: core::marker::PhantomData,
        })
    }

    /// Takes primary visibility from G-buffers (`(ray, hit)` for every eye ray, row-major
    /// and sample-major — `v[s * pixels + p]` — as the host's shadow caster computes
    /// them) instead of tracing eye rays.
    pub fn set_visibility(&mut self, v: Vec<(Option<Ray>, Option<Hit>)>) {
        self.visibility = Some(v);
    }

    /// Screen width and fragments per screen.
    pub(crate) fn screen(&self) -> (u32, usize) {
        (self.eye.width, (self.eye.width as usize) * (self.eye.height as usize))
    }

    /// Runs the frame; `progress(screens done, screens known)`.
    pub fn run(&mut self, mut progress: impl FnMut(usize, usize)) -> Result<(), String> {
        let samples = self.eye.samples() as usize;
        let (w, h) = (self.eye.width, self.eye.height);
        let (lo, hi) = self.scene.test_bounds();
        let cone = self.eye.cone();
        // Wave 0: one screen of eye rays per sample (Purcell's path tracer traces one
        // eye ray per sample).
        let mut wave: Vec<Vec<Fragment>> = Vec::with_capacity(samples);
        for s in 0..samples {
            let mut screen = Vec::with_capacity((w * h) as usize);
            for y in 0..h {
                for x in 0..w {
                    let p = y * w + x;
                    let record = |ray| RayRecord::eye_sample(ray, p, s as u32, samples as u32, cone);
                    let frag = match &self.visibility {
                        Some(v) => match v.get(s * (w * h) as usize + p as usize) {
                            Some(&(Some(ray), hit)) => Fragment::Visible(record(ray), hit),
                            _ => Fragment::Empty,
                        },
                        None => match self.eye.sample_ray_in_scene(x, y, s as u32, lo, hi) {
                            Some(ray) => Fragment::Trace(record(ray)),
                            None => Fragment::Empty,
                        },
                    };
                    screen.push(frag);
                }
            }
            wave.push(screen);
        }
        let mut screens_done = 0;
        let mut wave_index = 0u32;
        while !wave.is_empty() {
            if wave_index as usize >= MAX_WAVES {
                return Err(format!("the shader still emits rays after {MAX_WAVES} generations"));
            }
            let mut next: Vec<RayRecord> = Vec::new();
            let total = screens_done + wave.len();
            let mut traced = 0u64;
            for (s, screen) in wave.into_iter().enumerate() {
                traced += screen.iter().filter(|f| matches!(f, Fragment::Trace(_))).count() as u64;
                self.run_screen(wave_index, s as u32, screen, &mut next)?;
                screens_done += 1;
                progress(screens_done, total);
            }
            self.rays_by_wave.push(traced);
            // The emitted records, packed densely into screens.
            let (_, per_screen) = self.screen();
            wave = next.chunks(per_screen.max(1)).map(|c| c.iter().map(|r| Fragment::Trace(*r)).collect()).collect();
            wave_index += 1;
        }
        Ok(())
    }

    /// One screen: traversal by the architecture, then shading.
    fn run_screen(
        &mut self,
        wave: u32,
        screen: u32,
        frags: Vec<Fragment>,
        next: &mut Vec<RayRecord>,
    ) -> Result<(), String> {
        let rays: Vec<Option<(Ray, bool)>> = frags
            .iter()
            .map(|f| match f {
                Fragment::Trace(r) => Some((r.ray, r.kind == raypipe_core::shade::ray_record::RayKind::Shadow)),
                _ => None,
            })
            .collect();
        let traced = rays.iter().any(Option::is_some);
        let generate = wave == 0 && self.visibility.is_none();
        let mut fused = PassRecord { wave, screen, kind: Some(PassKind::Fused), ..Default::default() };
        let ends: Vec<Option<StreamRay<I>>> = if !traced {
            vec![None; frags.len()]
        } else {
            match self.cfg.arch {
                Architecture::Multipass => self.multipass_screen(wave, screen, &rays, generate)?,
                Architecture::Branching => self.branching_screen(&rays, generate, &mut fused),
            }
        };
        let (shade, written) = self.shading_pass(wave, screen, &frags, &ends, next);
        match self.cfg.arch {
            Architecture::Multipass => {
                let repeats = self.output_repeats(Kernel::Shade, &shade, written);
                self.passes.push(shade);
                self.passes.extend(repeats);
            }
            Architecture::Branching => {
                fused.processed += shade.processed;
                fused.useful += shade.useful;
                fused.instructions += shade.instructions;
                fused.state_read += shade.state_read;
                fused.state_written += shade.state_written;
                for c in 0..4 {
                    fused.random_words[c] += shade.random_words[c];
                }
                self.passes.push(fused);
            }
        }
        Ok(())
    }

    /// Charges `invocations` of kernel `k` to the totals and to `pass`: instructions
    /// (on the multipass machine, the kernel's per-pass part once for each of the
    /// `state_rays` rays processed), state words for `state_rays` rays (the multipass machine's state textures, or the
    /// branching machine's stream input and output), and random-access words (the
    /// measured ones, unless the cost table fixes them).
    pub(crate) fn charge(
        &mut self,
        k: Kernel,
        invocations: u64,
        state_rays: u64,
        measured: [u64; 4],
        pass: &mut PassRecord,
    ) {
        let c = self.costs.get(k);
        let (instructions, r, w) = match self.cfg.arch {
            // The pass's part once per processed ray, the rest per iteration.
            Architecture::Multipass => {
                (invocations * (c.instructions - c.per_pass.min(c.instructions)) + state_rays * c.per_pass, c.r, c.w)
            }
            Architecture::Branching => (invocations * c.b_instructions, c.br, c.bw),
        };
        let t = self.kernels.get_mut(k);
        t.invocations += invocations;
        t.instructions += instructions;
        pass.instructions += instructions;
        t.state_read += state_rays * r;
        t.state_written += state_rays * w;
        pass.state_read += state_rays * r;
        pass.state_written += state_rays * w;
        let words: u64 = measured.iter().sum();
        t.random_words += match c.m {
            Some(m) => m * invocations as f64,
            None => words as f64,
        };
        for (p, m) in pass.random_words.iter_mut().zip(measured) {
            *p += m;
        }
    }

    /// A multipass kernel that writes more words per fragment than a pass may output
    /// (`write_words` > `output_words`, §2.2) runs again over the same fragments for
    /// each further group of outputs: each repeat reads the stencil of every covered
    /// fragment, the kernel's state inputs, and executes the kernel's instructions once
    /// more (the program recomputes what it cannot carry over). The words written are
    /// already charged. Returns the repeats, to be pushed after `first`.
    pub(crate) fn output_repeats(&mut self, k: Kernel, first: &PassRecord, write_words: u64) -> Vec<PassRecord> {
        let per_pass = self.cfg.output_words.max(4) as u64;
        let extra = write_words.div_ceil(per_pass).saturating_sub(1);
        if self.cfg.arch != Architecture::Multipass || extra == 0 {
            return Vec::new();
        }
        let r = self.costs.get(k).r;
        let t = self.kernels.get_mut(k);
        let mut repeats = Vec::new();
        for _ in 0..extra {
            let mut p = PassRecord {
                wave: first.wave,
                screen: first.screen,
                kind: first.kind,
                iterations: 1,
                processed: first.processed,
                covered: first.covered,
                instructions: first.instructions,
                state_read: first.processed * r,
                active_after: first.active_after,
                ..Default::default()
            };
            p.stencil.reads = first.covered;
            t.instructions += p.instructions;
            t.state_read += p.state_read;
            repeats.push(p);
        }
        repeats
    }

    /// Folds one ray's work into the maxima.
    pub(crate) fn note_work(&mut self, w: &RayWork) {
        let m = &mut self.max_work;
        m.steps = m.steps.max(w.steps);
        m.intersections = m.intersections.max(w.intersections);
        m.traverse_passes = m.traverse_passes.max(w.traverse_passes);
        m.intersect_passes = m.intersect_passes.max(w.intersect_passes);
    }

    /// The image, 8-bit sRGB.
    pub fn image(&self) -> Vec<[u8; 3]> {
        self.radiance_image().into_iter().map(rgb8).collect()
    }

    /// The image, linear radiance: ray casting's colours with one sample per pixel, the
    /// exact sums of the samples' radiance otherwise.
    pub fn radiance_image(&self) -> Vec<Vec3> {
        if self.sums_radiance() {
            self.radiance.iter().map(RadianceSum::value).collect()
        } else {
            self.framebuffer.clone()
        }
    }

    /// Whether pixels are sums of weighted radiance (a shader, or several samples) rather
    /// than one colour.
    pub(crate) fn sums_radiance(&self) -> bool {
        self.shader.is_some() || self.eye.samples() > 1
    }

    /// Eye rays per pixel.
    pub(crate) fn samples(&self) -> u32 {
        self.eye.samples()
    }

    /// The report of the frame so far.
    pub fn report(&self) -> StreamReport {
        let cfg = self.config().clone();
        let passes = self.passes.clone();
        let count = |k: PassKind| passes.iter().filter(|p| p.kind == Some(k)).count() as u64;
        let sum = |k: PassKind, f: fn(&PassRecord) -> u64| -> u64 {
            passes.iter().filter(|p| p.kind == Some(k)).map(f).sum()
        };
        let (tp, ip) = (count(PassKind::Traverse), count(PassKind::Intersect));
        let (tu, ti) = (sum(PassKind::Traverse, |p| p.useful), sum(PassKind::Traverse, |p| p.idle));
        let (iu, ii) = (sum(PassKind::Intersect, |p| p.useful), sum(PassKind::Intersect, |p| p.idle));
        let fused = passes.iter().filter(|p| p.kind == Some(PassKind::Fused));
        let (fu, fi) = fused.fold((0, 0), |(u, i), p| (u + p.useful, i + p.idle));
        let multipass = cfg.arch == Architecture::Multipass;
        let table2 = Table2 {
            traverse_passes: tp,
            intersect_passes: ip,
            other_passes: passes.len() as u64 - tp - ip,
            total_passes: passes.len() as u64,
            max_steps: self.max_work.steps,
            max_intersections: self.max_work.intersections,
            optimal_passes: self.loops.bound,
            ratio_to_optimal: if multipass { ratio(tp + ip, self.loops.bound) } else { None },
            simd_traverse: ratio(tu, tu + ti),
            simd_intersect: ratio(iu, iu + ii),
            simd_overall: if multipass { ratio(tu + iu, tu + ti + iu + ii) } else { ratio(fu, fu + fi) },
            simd_screen: multipass.then(|| screen_efficiency(&passes)).flatten(),
        };
        let costs = self.costs().clone();
        let kernels = Kernel::ALL
            .iter()
            .map(|&k| {
                let c = costs.get(k);
                let t = *self.kernels.get(k);
                let mean = if t.invocations > 0 { t.random_words / t.invocations as f64 } else { 0.0 };
                let (instructions, r, w) =
                    if multipass { (c.instructions, c.r, c.w) } else { (c.b_instructions, c.br, c.bw) };
                KernelRow { kernel: k.name(), instructions, r, w, m: c.m.unwrap_or(mean), totals: t }
            })
            .collect();
        let cache = self.texture_cache();
        let stats = cache.stats;
        let classes: Vec<ClassRow> = (0..CLASSES)
            .filter(|&c| c != STATE || cfg.cache_state)
            .map(|c| ClassRow {
                class: CLASS_NAMES[c],
                words: stats.words[c],
                hit_rate: if cache.enabled() { stats.hit_rate(c) } else { None },
                bytes_without_cache: stats.words[c] * 4,
                bytes_with_cache: cache.bytes_fetched(c),
            })
            .collect();
        let state_read: u64 = passes.iter().map(|p| p.state_read).sum();
        let state_written: u64 = passes.iter().map(|p| p.state_written).sum();
        let stencil_reads: u64 = passes.iter().map(|p| p.stencil.reads).sum();
        let stencil_writes: u64 = passes.iter().map(|p| p.stencil.writes).sum();
        let scene_classes = 0..STATE;
        let random: u64 = scene_classes.clone().map(|c| cache.bytes_fetched(c)).sum();
        let random_uncached: u64 = scene_classes.map(|c| stats.words[c] * 4).sum();
        // With a table that fixes M, the table's words stand for the scene reads.
        let fixed_m = costs.kernels.values().any(|c| c.m.is_some());
        let table_words: f64 = self.kernels.0.iter().map(|t| t.random_words).sum();
        let random = if fixed_m { (table_words * 4.0) as u64 } else { random };
        // State reads that went through the cache cost its lines; the rest (the shading
        // pass's, the repeats', the branching machine's stream input) their words.
        let cached_state_words = if cfg.cache_state { stats.words[STATE] } else { 0 };
        let cached_state_bytes = if cfg.cache_state { cache.bytes_fetched(STATE) } else { 0 };
        let state_reads_bytes = cached_state_bytes + state_read.saturating_sub(cached_state_words) * 4;
        let state = state_reads_bytes + state_written * 4;
        let stencil = stencil_reads + stencil_writes;
        let traffic = Traffic { random, random_uncached, state, stencil, total: random + state + stencil };
        let instructions = self.kernels.instructions();
        StreamReport {
            width: self.size().0,
            height: self.size().1,
            frame_time: cfg.machine.frame_time(instructions, traffic.total),
            config: cfg,
            costs,
            table2,
            kernels,
            classes,
            instructions,
            state_read,
            state_written,
            stencil_reads,
            stencil_writes,
            traffic,
            cache: stats,
            rays_by_wave: self.rays_by_wave.clone(),
            max_work: self.max_work,
            passes,
        }
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.eye.width, self.eye.height)
    }

    /// The configuration.
    pub fn config(&self) -> &StreamConfig {
        &self.cfg
    }

    /// The cost table.
    pub fn costs(&self) -> &CostModel {
        &self.costs
    }

    /// The texture cache.
    pub fn texture_cache(&self) -> &TextureCache {
        &self.cache
    }
}

/// Purcell's SIMD efficiency: the mean, over the traversal and intersection passes, of
/// each pass's fraction of screen rays doing useful work.
fn screen_efficiency(passes: &[PassRecord]) -> Option<f64> {
    let loops = passes.iter().filter(|p| matches!(p.kind, Some(PassKind::Traverse | PassKind::Intersect)));
    let (sum, n) = loops.filter_map(PassRecord::screen_efficiency).fold((0.0, 0u64), |(s, n), e| (s + e, n + 1));
    (n > 0).then(|| sum / n as f64)
}
