/work/main/core/capi/target/release/deps/raypipe_core-8f1b71c8f7e5d594.d: /work/main/core/src/lib.rs /work/main/core/src/camera.rs /work/main/core/src/counters.rs /work/main/core/src/cpu.rs /work/main/core/src/hit.rs /work/main/core/src/image/mod.rs /work/main/core/src/image/crc32.rs /work/main/core/src/image/embed.rs /work/main/core/src/image/header.rs /work/main/core/src/image/records.rs /work/main/core/src/image/view.rs /work/main/core/src/intersect/mod.rs /work/main/core/src/intersect/leaf_blocks.rs /work/main/core/src/intersect/moller_trumbore.rs /work/main/core/src/intersect/triangle.rs /work/main/core/src/intersect/wald.rs /work/main/core/src/intersect/watertight.rs /work/main/core/src/intersect/watertight8.rs /work/main/core/src/packet/mod.rs /work/main/core/src/packet/bvh.rs /work/main/core/src/packet/bvh4.rs /work/main/core/src/packet/bvh_step.rs /work/main/core/src/packet/grid.rs /work/main/core/src/packet/kdtree.rs /work/main/core/src/packet/kdtree_step.rs /work/main/core/src/packet/lockstep.rs /work/main/core/src/packet/step.rs /work/main/core/src/packet/wide_bvh_step.rs /work/main/core/src/probe.rs /work/main/core/src/ray.rs /work/main/core/src/shade/mod.rs /work/main/core/src/shade/color.rs /work/main/core/src/shade/lambert.rs /work/main/core/src/shade/path.rs /work/main/core/src/shade/radiance_sum.rs /work/main/core/src/shade/raster.rs /work/main/core/src/shade/ray_record.rs /work/main/core/src/shade/rng.rs /work/main/core/src/shade/shader.rs /work/main/core/src/shade/specular.rs /work/main/core/src/shade/surface.rs /work/main/core/src/shade/texture.rs /work/main/core/src/shade/whitted.rs /work/main/core/src/traverse/mod.rs /work/main/core/src/traverse/aabb.rs /work/main/core/src/traverse/brute_force.rs /work/main/core/src/traverse/bvh.rs /work/main/core/src/traverse/bvh4.rs /work/main/core/src/traverse/bvh8.rs /work/main/core/src/traverse/dda.rs /work/main/core/src/traverse/grid.rs /work/main/core/src/traverse/kdtree.rs /work/main/core/src/traverse/occlusion.rs /work/main/core/src/traverse/ray_box.rs /work/main/core/src/traverse/tree_step.rs /work/main/core/src/traverse/walk.rs /work/main/core/src/traverse/wide_bvh.rs

/work/main/core/capi/target/release/deps/libraypipe_core-8f1b71c8f7e5d594.rlib: /work/main/core/src/lib.rs /work/main/core/src/camera.rs /work/main/core/src/counters.rs /work/main/core/src/cpu.rs /work/main/core/src/hit.rs /work/main/core/src/image/mod.rs /work/main/core/src/image/crc32.rs /work/main/core/src/image/embed.rs /work/main/core/src/image/header.rs /work/main/core/src/image/records.rs /work/main/core/src/image/view.rs /work/main/core/src/intersect/mod.rs /work/main/core/src/intersect/leaf_blocks.rs /work/main/core/src/intersect/moller_trumbore.rs /work/main/core/src/intersect/triangle.rs /work/main/core/src/intersect/wald.rs /work/main/core/src/intersect/watertight.rs /work/main/core/src/intersect/watertight8.rs /work/main/core/src/packet/mod.rs /work/main/core/src/packet/bvh.rs /work/main/core/src/packet/bvh4.rs /work/main/core/src/packet/bvh_step.rs /work/main/core/src/packet/grid.rs /work/main/core/src/packet/kdtree.rs /work/main/core/src/packet/kdtree_step.rs /work/main/core/src/packet/lockstep.rs /work/main/core/src/packet/step.rs /work/main/core/src/packet/wide_bvh_step.rs /work/main/core/src/probe.rs /work/main/core/src/ray.rs /work/main/core/src/shade/mod.rs /work/main/core/src/shade/color.rs /work/main/core/src/shade/lambert.rs /work/main/core/src/shade/path.rs /work/main/core/src/shade/radiance_sum.rs /work/main/core/src/shade/raster.rs /work/main/core/src/shade/ray_record.rs /work/main/core/src/shade/rng.rs /work/main/core/src/shade/shader.rs /work/main/core/src/shade/specular.rs /work/main/core/src/shade/surface.rs /work/main/core/src/shade/texture.rs /work/main/core/src/shade/whitted.rs /work/main/core/src/traverse/mod.rs /work/main/core/src/traverse/aabb.rs /work/main/core/src/traverse/brute_force.rs /work/main/core/src/traverse/bvh.rs /work/main/core/src/traverse/bvh4.rs /work/main/core/src/traverse/bvh8.rs /work/main/core/src/traverse/dda.rs /work/main/core/src/traverse/grid.rs /work/main/core/src/traverse/kdtree.rs /work/main/core/src/traverse/occlusion.rs /work/main/core/src/traverse/ray_box.rs /work/main/core/src/traverse/tree_step.rs /work/main/core/src/traverse/walk.rs /work/main/core/src/traverse/wide_bvh.rs

/work/main/core/capi/target/release/deps/libraypipe_core-8f1b71c8f7e5d594.rmeta: /work/main/core/src/lib.rs /work/main/core/src/camera.rs /work/main/core/src/counters.rs /work/main/core/src/cpu.rs /work/main/core/src/hit.rs /work/main/core/src/image/mod.rs /work/main/core/src/image/crc32.rs /work/main/core/src/image/embed.rs /work/main/core/src/image/header.rs /work/main/core/src/image/records.rs /work/main/core/src/image/view.rs /work/main/core/src/intersect/mod.rs /work/main/core/src/intersect/leaf_blocks.rs /work/main/core/src/intersect/moller_trumbore.rs /work/main/core/src/intersect/triangle.rs /work/main/core/src/intersect/wald.rs /work/main/core/src/intersect/watertight.rs /work/main/core/src/intersect/watertight8.rs /work/main/core/src/packet/mod.rs /work/main/core/src/packet/bvh.rs /work/main/core/src/packet/bvh4.rs /work/main/core/src/packet/bvh_step.rs /work/main/core/src/packet/grid.rs /work/main/core/src/packet/kdtree.rs /work/main/core/src/packet/kdtree_step.rs /work/main/core/src/packet/lockstep.rs /work/main/core/src/packet/step.rs /work/main/core/src/packet/wide_bvh_step.rs /work/main/core/src/probe.rs /work/main/core/src/ray.rs /work/main/core/src/shade/mod.rs /work/main/core/src/shade/color.rs /work/main/core/src/shade/lambert.rs /work/main/core/src/shade/path.rs /work/main/core/src/shade/radiance_sum.rs /work/main/core/src/shade/raster.rs /work/main/core/src/shade/ray_record.rs /work/main/core/src/shade/rng.rs /work/main/core/src/shade/shader.rs /work/main/core/src/shade/specular.rs /work/main/core/src/shade/surface.rs /work/main/core/src/shade/texture.rs /work/main/core/src/shade/whitted.rs /work/main/core/src/traverse/mod.rs /work/main/core/src/traverse/aabb.rs /work/main/core/src/traverse/brute_force.rs /work/main/core/src/traverse/bvh.rs /work/main/core/src/traverse/bvh4.rs /work/main/core/src/traverse/bvh8.rs /work/main/core/src/traverse/dda.rs /work/main/core/src/traverse/grid.rs /work/main/core/src/traverse/kdtree.rs /work/main/core/src/traverse/occlusion.rs /work/main/core/src/traverse/ray_box.rs /work/main/core/src/traverse/tree_step.rs /work/main/core/src/traverse/walk.rs /work/main/core/src/traverse/wide_bvh.rs

/work/main/core/src/lib.rs:
/work/main/core/src/camera.rs:
/work/main/core/src/counters.rs:
/work/main/core/src/cpu.rs:
/work/main/core/src/hit.rs:
/work/main/core/src/image/mod.rs:
/work/main/core/src/image/crc32.rs:
/work/main/core/src/image/embed.rs:
/work/main/core/src/image/header.rs:
/work/main/core/src/image/records.rs:
/work/main/core/src/image/view.rs:
/work/main/core/src/intersect/mod.rs:
/work/main/core/src/intersect/leaf_blocks.rs:
/work/main/core/src/intersect/moller_trumbore.rs:
/work/main/core/src/intersect/triangle.rs:
/work/main/core/src/intersect/wald.rs:
/work/main/core/src/intersect/watertight.rs:
/work/main/core/src/intersect/watertight8.rs:
/work/main/core/src/packet/mod.rs:
/work/main/core/src/packet/bvh.rs:
/work/main/core/src/packet/bvh4.rs:
/work/main/core/src/packet/bvh_step.rs:
/work/main/core/src/packet/grid.rs:
/work/main/core/src/packet/kdtree.rs:
/work/main/core/src/packet/kdtree_step.rs:
/work/main/core/src/packet/lockstep.rs:
/work/main/core/src/packet/step.rs:
/work/main/core/src/packet/wide_bvh_step.rs:
/work/main/core/src/probe.rs:
/work/main/core/src/ray.rs:
/work/main/core/src/shade/mod.rs:
/work/main/core/src/shade/color.rs:
/work/main/core/src/shade/lambert.rs:
/work/main/core/src/shade/path.rs:
/work/main/core/src/shade/radiance_sum.rs:
/work/main/core/src/shade/raster.rs:
/work/main/core/src/shade/ray_record.rs:
/work/main/core/src/shade/rng.rs:
/work/main/core/src/shade/shader.rs:
/work/main/core/src/shade/specular.rs:
/work/main/core/src/shade/surface.rs:
/work/main/core/src/shade/texture.rs:
/work/main/core/src/shade/whitted.rs:
/work/main/core/src/traverse/mod.rs:
/work/main/core/src/traverse/aabb.rs:
/work/main/core/src/traverse/brute_force.rs:
/work/main/core/src/traverse/bvh.rs:
/work/main/core/src/traverse/bvh4.rs:
/work/main/core/src/traverse/bvh8.rs:
/work/main/core/src/traverse/dda.rs:
/work/main/core/src/traverse/grid.rs:
/work/main/core/src/traverse/kdtree.rs:
/work/main/core/src/traverse/occlusion.rs:
/work/main/core/src/traverse/ray_box.rs:
/work/main/core/src/traverse/tree_step.rs:
/work/main/core/src/traverse/walk.rs:
/work/main/core/src/traverse/wide_bvh.rs:
