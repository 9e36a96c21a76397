//! Placeholder; replaced by the real criterion benches.
fn main() {}
