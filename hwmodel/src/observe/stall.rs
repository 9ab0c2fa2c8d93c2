//! Why a unit stalled: every stall cycle of every unit is attributed to exactly one
//! reason, so an architect can see where time goes (gem5's and Vulkan-Sim's stall
//! breakdowns). The reasons of one cycle are ranked: what the unit's oldest waiting work
//! waits for comes first.

/// A reason for a stall cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stall {
    /// Waiting for node (grid cell, tree node) data from memory.
    NodeData,
    /// Waiting for primitive-list or triangle data from memory.
    TriangleData,
    /// Waiting for shading data from memory.
    ShadingData,
    /// A miss could not start: every MSHR of its cache is busy.
    Mshr,
    /// A request could not leave: the memory's request queue is full.
    MemoryQueue,
    /// Lookups waiting for a cache port.
    CachePort,
    /// A traversal step in its pipeline (step latency).
    StepLatency,
    /// Tests in the intersection pipeline (latency), or shading in its datapath.
    PipelineLatency,
    /// Every packet in flight is at the intersection unit.
    AtIntersection,
    /// A finished packet or job waits for room in its output FIFO.
    OutputFull,
    /// A thread is ready but another one took the issue slot.
    IssueSlot,
    /// Rays entering instances wait for the transformation unit.
    Transform,
}

/// Number of reasons.
pub const STALLS: usize = 12;

impl Stall {
    /// Every reason, in report order.
    pub const ALL: [Stall; STALLS] = [
        Stall::NodeData,
        Stall::TriangleData,
        Stall::ShadingData,
        Stall::Mshr,
        Stall::MemoryQueue,
        Stall::CachePort,
        Stall::StepLatency,
        Stall::PipelineLatency,
        Stall::AtIntersection,
        Stall::OutputFull,
        Stall::IssueSlot,
        Stall::Transform,
    ];

    /// The report's name.
    pub const fn name(self) -> &'static str {
        match self {
            Stall::NodeData => "node_data",
            Stall::TriangleData => "triangle_data",
            Stall::ShadingData => "shading_data",
            Stall::Mshr => "mshr",
            Stall::MemoryQueue => "memory_queue_full",
            Stall::CachePort => "cache_port",
            Stall::StepLatency => "step_latency",
            Stall::PipelineLatency => "pipeline_latency",
            Stall::AtIntersection => "all_threads_at_intersection",
            Stall::OutputFull => "output_fifo_full",
            Stall::IssueSlot => "issue_slot",
            Stall::Transform => "transform_unit",
        }
    }

    /// The kind of wait, for sentences that must add up: memory (data not yet there),
    /// back-pressure (no room downstream), pipeline (the unit's own latency and issue
    /// slots) or starvation (nothing of its own to work on).
    pub const fn group(self) -> &'static str {
        match self {
            Stall::NodeData | Stall::TriangleData | Stall::ShadingData | Stall::Mshr | Stall::MemoryQueue => "memory",
            Stall::OutputFull => "a full output FIFO",
            Stall::StepLatency | Stall::PipelineLatency | Stall::IssueSlot | Stall::CachePort => "their pipeline",
            Stall::AtIntersection => "the intersection unit",
            Stall::Transform => "the transformation unit",
        }
    }
}
