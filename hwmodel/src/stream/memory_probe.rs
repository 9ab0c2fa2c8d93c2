//! The stream machine's view of core's scene reads: each read goes through the texture
//! cache in fragment order and is counted as random-access words of its class. The
//! reads of a ray's last iteration are kept so that an unrolled iteration running on a
//! ray already done with the kernel can issue them again (a fragment program that
//! cannot branch fetches with its frozen state's addresses) unless references are
//! suppressed.

use raypipe_core::{DataClass, MemoryProbe};

use crate::stream::texture_cache::TextureCache;

/// Counts and forwards one kernel invocation's reads.
pub struct StreamProbe<'c> {
    cache: &'c mut TextureCache,
    /// Words read by class since the probe was made.
    pub words: [u64; 4],
    log: Vec<(DataClass, u32, u32)>,
    /// Keep the reads for [`StreamProbe::replay`] (only unrolled, unsuppressed passes
    /// replay).
    logging: bool,
}

impl<'c> StreamProbe<'c> {
    /// A probe in front of `cache`; `replays`: an iteration's reads may be issued again.
    pub fn new(cache: &'c mut TextureCache, replays: bool) -> StreamProbe<'c> {
        StreamProbe { cache, words: [0; 4], log: Vec::new(), logging: replays }
    }

    /// Starts an iteration: forgets the previous one's reads.
    pub fn begin(&mut self) {
        self.log.clear();
    }

    /// Issues the last iteration's reads again.
    pub fn replay(&mut self) {
        for i in 0..self.log.len() {
            let (class, addr, bytes) = self.log[i];
            self.count(class, addr, bytes);
        }
    }

    /// Total words read.
    pub fn total(&self) -> u64 {
        self.words.iter().sum()
    }

    /// Takes the word counts, leaving zeros.
    pub fn take_words(&mut self) -> [u64; 4] {
        core::mem::take(&mut self.words)
    }

    /// A state-texture read (through the cache if it is so configured).
    pub fn state_read(&mut self, addr: u64, words: u64) {
        self.cache.read(crate::stream::texture_cache::STATE, addr, (words * 4) as u32);
    }

    fn count(&mut self, class: DataClass, addr: u32, bytes: u32) {
        self.words[class as usize] += (bytes as u64).div_ceil(4);
        self.cache.read(class as usize, addr as u64, bytes);
    }
}

impl MemoryProbe for StreamProbe<'_> {
    fn read(&mut self, class: DataClass, addr: u32, bytes: u32) {
        if self.logging {
            self.log.push((class, addr, bytes));
        }
        self.count(class, addr, bytes);
    }
}
