//! The elastic catenary of one sling leg (Irvine, Cable Structures, 1981,
//! §2), shared by the sling tests.

/// Elastic catenary (Irvine) of one leg hanging between its top anchor and
/// the apex, with the apex pulled down by `v0` (N): unstretched length `l`,
/// weight `w` (N/m), axial stiffness `ea`, horizontal span `span`. Returns
/// (the depth of the apex below the anchor, the horizontal force H).
pub fn irvine_leg(l: f64, w: f64, ea: f64, span: f64, v0: f64) -> (f64, f64) {
    let x = |h: f64| h * l / ea + h / w * (((v0 + w * l) / h).asinh() - (v0 / h).asinh());
    let (mut lo, mut hi) = (1e-6f64, 1e9f64);
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if x(mid) < span {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let h = (lo * hi).sqrt();
    let root = |v: f64| (1.0 + (v / h).powi(2)).sqrt();
    let depth = v0 * l / ea + w * l * l / (2.0 * ea) + h / w * (root(v0 + w * l) - root(v0));
    (depth, h)
}
