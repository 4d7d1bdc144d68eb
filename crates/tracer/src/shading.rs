//! Which normal a BSDF sees — the lecture's question "which is the right normal?" — at
//! a hit with a geometric normal (from the winding) and an interpolated shading normal.

use glam::Vec3;

/// Which normal a BSDF sees — the lecture's question "which is the right normal?".
///
/// The geometric normal n_g (from the winding) decides on which side of the surface a
/// direction lies: whether a path arrives from outside or inside glass, and whether a
/// reflected direction stays above the surface. The interpolated shading normal n_s
/// only orients the BSDF's local frame. Near silhouettes of smooth meshes the two
/// disagree: the viewer may be above the surface but below the shading hemisphere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadingNormals {
    /// n_s, bent towards the outgoing direction where it disagrees with n_g about the side
    /// of ω_o ([`adapt_shading_normal`]); the side itself always comes from n_g, so
    /// glass knows when a path leaves it. No black silhouettes, exits kept.
    #[default]
    Adapted,
    /// The thesis's workaround: both normals turned to face the incoming path. Opaque
    /// surfaces look right, but every hit on glass becomes an entry — a path inside
    /// glass refracts with the inverted index and Beer–Lambert absorption never applies.
    FaceForward,
    /// Ignore shading normals (flat shading): exact, but faceted.
    Geometric,
}

impl ShadingNormals {
    /// Every mode, in the order of [`ShadingNormals::code`].
    pub const ALL: [ShadingNormals; 3] = [Self::Adapted, Self::FaceForward, Self::Geometric];

    /// The mode's number in GPU kernels (its position in [`ShadingNormals::ALL`]).
    pub fn code(self) -> u32 {
        self as u32
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Adapted => "adapted",
            Self::FaceForward => "face-forward",
            Self::Geometric => "geometric",
        }
    }
}

/// The smallest |ω_o · n_s| an adapted shading normal keeps, so that the BSDF's frame is
/// never edge-on to the outgoing direction.
pub const MIN_SHADING_COSINE: f32 = 0.01;

/// Bends the unit shading normal `ns` so that the outgoing direction `wo` lies on the same
/// side of it as of the geometric normal `ng` (both unit, `ns` on `ng`'s side), with
/// |ω_o · n_s| ≥ a small margin: n_s' = normalize(n_s + k·s·ω_o), s = sign(ω_o · n_g),
/// with k the least that reaches the margin. It moves continuously with ω_o (no seams),
/// changes nothing where the normals agree, and stays on n_g's side of the plane. Where
/// ω_o is on the other side of n_s than of n_g, a BSDF in n_s's frame would see the
/// viewer below its surface (black silhouettes on smooth meshes) or, for glass, mistake
/// an exit for an entry.
#[inline]
pub fn adapt_shading_normal(ns: Vec3, ng: Vec3, wo: Vec3) -> Vec3 {
    let side = if wo.dot(ng) >= 0.0 { 1.0 } else { -1.0 };
    let a = side * wo.dot(ns);
    if a >= MIN_SHADING_COSINE {
        return ns;
    }
    let bent = ns + (MIN_SHADING_COSINE - a) * side * wo;
    bent.try_normalize().unwrap_or(ng)
}

/// The geometric and shading normals a BSDF at a hit sees, from the surface's `ng` and
/// `ns` (on the same side) and the outgoing direction `wo`: two-sided (opaque) BSDFs see
/// the side the path arrived on as their front; transmissive ones keep the geometric
/// orientation, which tells an entry from an exit. The shading normal is adapted per
/// [`ShadingNormals`].
#[inline]
pub fn shading_normals(mode: ShadingNormals, ng: Vec3, ns: Vec3, wo: Vec3, two_sided: bool) -> (Vec3, Vec3) {
    let front = wo.dot(ng) > 0.0;
    match mode {
        ShadingNormals::FaceForward if !front => (-ng, -ns),
        ShadingNormals::FaceForward => (ng, ns),
        _ => {
            let ns = adapt_shading_normal(ns, ng, wo);
            if two_sided && !front { (-ng, -ns) } else { (ng, ns) }
        }
    }
}

#[cfg(test)]
mod tests;
