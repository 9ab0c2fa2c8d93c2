//! Embedding a scene image in a binary with the alignment [`SceneView::parse`] requires.
//!
//! [`SceneView::parse`]: crate::SceneView::parse

/// A wrapper that aligns its contents to a 64-byte cache line.
#[repr(C, align(64))]
pub struct Aligned64<B: ?Sized>(pub B);

/// Includes a scene image file as a `&'static [u8]` aligned to 64 bytes, ready for
/// [`SceneView::parse`](crate::SceneView::parse). `include_bytes!` alone gives no
/// alignment guarantee.
///
/// ```ignore
/// static SCENE: &[u8] = raypipe_core::include_scene!("scene.rpsi");
/// let view = raypipe_core::SceneView::parse(SCENE).unwrap();
/// ```
#[macro_export]
macro_rules! include_scene {
    ($path:expr) => {{
        static ALIGNED: &$crate::image::Aligned64<[u8]> = &$crate::image::Aligned64(*include_bytes!($path));
        &ALIGNED.0
    }};
}
