//! Coverage-guided fuzzing of scene input (AFL++ through `cargo afl`, stable Rust): see
//! `scanline3d_sim::fuzz` for what the bytes mean. Run it with `cargo xtask fuzz SECONDS`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        scanline3d_sim::fuzz::one(data);
    });
}
