//! What the waveform and the trace read off the chip, without changing it: the signals
//! sampled after each clock edge (FIFO occupancies, unit activities, threads by state,
//! requests waiting per port, the memory's queue; in a two-level scene the
//! transformation units' activity and requests waiting) and the events logged each cycle
//! (FIFO pushes and pops, packets shaded, memory transactions).

use raypipe_core::intersect::triangle::Intersector;

use crate::chip::simulator::{port_label, Simulator};
use crate::chip::traversal_unit::STATE_NAMES;
use crate::memory::port::MemPort;
use crate::memory::traffic::CLASS_NAMES;
use crate::observe::stall::STALLS;
use crate::observe::waves::{activity_code, Signal, TraceEvent, TraceLog, Waves};

impl<I: Intersector> Simulator<'_, I> {
    /// Every waveform signal, in [`Simulator::sample_signals`] order: FIFO occupancies,
    /// unit activities (0 idle, 1 busy, 2 + stall reason), traversal threads by state,
    /// requests waiting in each port, the memory's queue and the requests it took.
    pub fn signals(&self) -> Vec<Signal> {
        let bits = |max: u64| 64 - max.max(1).leading_zeros();
        let mut s: Vec<Signal> = self
            .fifos()
            .map(|f| Signal { name: format!("fifos.{}.occupancy", f.name()), width: bits(f.depth() as u64) })
            .collect();
        let activity = |unit: &str| Signal { name: format!("{unit}.activity"), width: bits(1 + STALLS as u64) };
        s.push(activity("rgs.generate"));
        s.push(activity("rgs.shade"));
        for t in &self.tus {
            s.push(activity(&format!("traversal{}", t.id)));
            for name in STATE_NAMES {
                s.push(Signal {
                    name: format!("traversal{}.threads.{name}", t.id),
                    width: bits(self.cfg.traversal.threads as u64),
                });
            }
        }
        for i in &self.ius {
            s.push(activity(&format!("intersection{}", i.id)));
        }
        for t in self.tus.iter().filter(|_| self.is_two_level()) {
            s.push(activity(&format!("transform{}", t.id)));
            s.push(Signal {
                name: format!("transform{}.waiting", t.id),
                width: bits(self.cfg.traversal.threads as u64),
            });
        }
        for p in self.ports() {
            s.push(Signal { name: format!("memory.ports.{}.waiting", port_label(p)), width: 16 });
        }
        s.push(Signal { name: "memory.queue".into(), width: bits(self.cfg.memory.queue_depth as u64) });
        s.push(Signal { name: "memory.requests".into(), width: 16 });
        s
    }

    /// The signals' current values.
    pub fn sample_signals(&self, out: &mut Vec<u64>) {
        out.clear();
        out.extend(self.fifos().map(|f| f.occupancy() as u64));
        out.push(activity_code(&self.rgs.gen_stats));
        out.push(activity_code(&self.rgs.shade_stats));
        for t in &self.tus {
            out.push(activity_code(&t.stats));
            out.extend(t.thread_states());
        }
        out.extend(self.ius.iter().map(|i| activity_code(&i.stats)));
        for t in self.tus.iter().filter(|_| self.is_two_level()) {
            out.push(activity_code(&t.transform.stats));
            out.push(t.transform.waiting());
        }
        out.extend(self.ports().map(|p| p.staged.len() as u64));
        out.push(self.memory.queue_len() as u64);
        out.push(self.accepted);
    }

    pub(crate) fn ports(&self) -> impl Iterator<Item = &MemPort> {
        std::iter::once(&self.rgs.port).chain(self.tus.iter().map(|t| &t.port)).chain(self.ius.iter().map(|i| &i.port))
    }

    /// Writes waveforms to `waves` from now on.
    pub fn set_waves(&mut self, waves: Waves) {
        self.waves = Some(waves);
    }

    /// Stops writing waveforms: the sampler, to be finished by the caller.
    pub fn take_waves(&mut self) -> Option<Waves> {
        self.waves.take()
    }

    /// Records packet lifetimes and memory transactions from now on.
    pub fn enable_trace(&mut self) {
        self.trace = Some(TraceLog::default());
        self.ray_fifos.iter_mut().for_each(|f| f.enable_log(|j| j.index));
        self.leaf_fifos.iter_mut().for_each(|f| f.enable_log(|j| j.packet));
        self.result_fifos.iter_mut().for_each(|f| f.enable_log(|j| j.packet));
        self.hit_fifos.iter_mut().for_each(|f| f.enable_log(|j| j.index));
        self.rgs.done_log = Some(Vec::new());
        self.rgs.port.log = Some(Vec::new());
        self.tus.iter_mut().for_each(|t| t.port.log = Some(Vec::new()));
        self.ius.iter_mut().for_each(|i| i.port.log = Some(Vec::new()));
    }

    /// The trace recorded so far.
    pub fn take_trace(&mut self) -> Option<TraceLog> {
        self.trace.take()
    }

    /// Moves this cycle's logged events into the trace, stamped with `now`.
    pub(crate) fn record_trace(&mut self, now: u64) {
        let Some(mut trace) = self.trace.take() else { return };
        let frame = self.frame;
        let mut entries = Vec::new();
        for f in self.fifos_mut() {
            f.take_log(&mut entries);
            let name = f.name().to_string();
            for (push, packet) in entries.drain(..) {
                trace.events.push(TraceEvent::Fifo { cycle: now, fifo: name.clone(), push, packet });
                trace.frames.push(frame);
            }
        }
        if let Some(done) = self.rgs.done_log.as_mut() {
            for packet in done.drain(..) {
                trace.events.push(TraceEvent::Shaded { cycle: now, packet });
                trace.frames.push(frame);
            }
        }
        let ports = std::iter::once(&mut self.rgs.port)
            .chain(self.tus.iter_mut().map(|t| &mut t.port))
            .chain(self.ius.iter_mut().map(|i| &mut i.port));
        for p in ports {
            let label = port_label(p);
            if let Some(log) = p.log.as_mut() {
                for (r, ready) in log.drain(..) {
                    trace.events.push(TraceEvent::Memory {
                        port: label.clone(),
                        issued: r.issued,
                        ready,
                        class: CLASS_NAMES[r.class],
                        bytes: r.bytes,
                        write: r.write,
                    });
                    trace.frames.push(frame);
                }
            }
        }
        self.trace = Some(trace);
    }
}
