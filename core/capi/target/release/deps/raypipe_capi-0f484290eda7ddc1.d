/work/main/core/capi/target/release/deps/raypipe_capi-0f484290eda7ddc1.d: src/lib.rs Cargo.toml

/work/main/core/capi/target/release/deps/libraypipe_capi-0f484290eda7ddc1.rmeta: src/lib.rs Cargo.toml

src/lib.rs:
Cargo.toml:

# env-dep:CLIPPY_ARGS=-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__
# env-dep:CLIPPY_CONF_DIR
