/work/main/core/capi/target/release/deps/raypipe_capi-9e91379c476e034f.d: src/lib.rs

/work/main/core/capi/target/release/deps/libraypipe_capi-9e91379c476e034f.a: src/lib.rs

src/lib.rs:
