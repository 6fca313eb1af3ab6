//! x86-64 kernels that use AVX2 and FMA when the CPU has them (checked at run time; the
//! portable glam paths in the job files run otherwise). Same formulas, fused multiply-adds
//! and 256-bit registers: a 3×4 palette matrix is two registers, (x | y) and (z | t), so
//! blending one influence is two FMAs instead of eight SSE multiplies and adds.

use std::arch::x86_64::*;
use std::sync::OnceLock;

use glam::{Affine3A, Mat3A, Vec3, Vec3A, Vec4};

use super::trig::sin_cos_quarter_turn;
use crate::dual_quat::DualQuat;
use crate::influences::BonesBlendVertex;
use crate::pose::BonesBlendJoint;

/// The CPU features the kernels' builds need: as this CPU reports them ([`Features::detect`]),
/// or as a test states them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Features {
    pub(crate) avx2: bool,
    pub(crate) fma: bool,
    pub(crate) avx512f: bool,
    pub(crate) avx512vl: bool,
}

impl Features {
    /// This CPU's features (std caches the detection).
    pub(crate) fn detect() -> Features {
        Features {
            avx2: is_x86_feature_detected!("avx2"),
            fma: is_x86_feature_detected!("fma"),
            avx512f: is_x86_feature_detected!("avx512f"),
            avx512vl: is_x86_feature_detected!("avx512vl"),
        }
    }

    /// Whether a CPU with these features can run the AVX2 + FMA kernels below.
    pub(crate) fn run_avx2_fma(self) -> bool {
        self.avx2 && self.fma
    }

    /// Whether it can also run the AVX-512VL builds of the kernels (32 vector registers).
    pub(crate) fn run_avx512vl(self) -> bool {
        self.run_avx2_fma() && self.avx512f && self.avx512vl
    }
}

/// Bytes a linear-blend or dual-quaternion job reads and writes per vertex with `influences`
/// influences: position and normal in and out (4 × 12) and per influence a 16-bit joint index
/// and an f32 weight — 72 with four influences, as docs/skinning-vs-ozz.md counts them.
#[must_use]
pub(crate) const fn bytes_per_vertex(influences: usize) -> usize {
    4 * 12 + influences * (2 + 4)
}

/// Whether a job of `vertices` vertices with `influences` influences each, which reads and writes
/// [`bytes_per_vertex`] per vertex, should write its outputs with streaming
/// (non-temporal) stores: when the job is larger than the CPU's last-level cache, so that its
/// first outputs are evicted before it ends and no reader finds them in the cache anyway. Then
/// streaming stores save the read of every output cache line before it is written (a third of
/// linear blend's memory traffic at 1 000 000 vertices). Smaller jobs keep their outputs cached
/// for whoever reads them next. Never when the cache size is unknown.
pub(crate) fn streams_outputs(vertices: usize, influences: usize) -> bool {
    larger_than_cache(vertices, influences, last_level_cache_bytes())
}

/// Whether `vertices` vertices of `influences` influences move more bytes than a `cache` of
/// that size holds; never when its size is unknown.
fn larger_than_cache(vertices: usize, influences: usize, cache: Option<usize>) -> bool {
    cache.is_some_and(|cache| vertices.saturating_mul(bytes_per_vertex(influences)) > cache)
}

/// The size of this CPU's last-level cache ([`last_level_cache_from`] on its CPUID), read once.
fn last_level_cache_bytes() -> Option<usize> {
    static SIZE: OnceLock<Option<usize>> = OnceLock::new();
    *SIZE.get_or_init(|| {
        last_level_cache_from(|leaf, sub_leaf| {
            let r = __cpuid_count(leaf, sub_leaf);
            [r.eax, r.ebx, r.ecx, r.edx]
        })
    })
}

/// The size of the highest-level data or unified cache, from CPUID's deterministic cache
/// parameters (leaf 4 on Intel, 0x8000_001D on AMD and Hygon when they have topology
/// extensions); `None` when the CPU does not report them. `cpuid(leaf, sub_leaf)` returns EAX,
/// EBX, ECX and EDX.
fn last_level_cache_from(cpuid: impl Fn(u32, u32) -> [u32; 4]) -> Option<usize> {
    const AMD: [u32; 3] = [0x6874_7541, 0x6974_6E65, 0x444D_4163]; // "AuthenticAMD" in EBX, EDX, ECX
    const HYGON: [u32; 3] = [0x6F67_7948, 0x6E65_476E, 0x656E_6975]; // "HygonGenuine"
    let [max_leaf, b, c, d] = cpuid(0, 0);
    let leaf = if [b, d, c] == AMD || [b, d, c] == HYGON {
        let topology_extensions =
            cpuid(0x8000_0000, 0)[0] >= 0x8000_001D && cpuid(0x8000_0001, 0)[2] & (1 << 22) != 0;
        topology_extensions.then_some(0x8000_001D)?
    } else {
        (max_leaf >= 4).then_some(4)?
    };
    // Sub-leaf i describes one cache until its type (bits 4..0 of EAX) is 0: 1 data, 2
    // instruction, 3 unified; level in bits 7..5; ways, partitions and line size minus one in
    // EBX's bits 31..22, 21..12 and 11..0; sets minus one in ECX.
    (0..16)
        .map(|i| cpuid(leaf, i))
        .take_while(|[eax, ..]| eax & 0x1F != 0)
        .filter(|[eax, ..]| matches!(eax & 0x1F, 1 | 3))
        .map(|[eax, ebx, ecx, _]| {
            let ways = (ebx >> 22) as usize + 1;
            let partitions = ((ebx >> 12) & 0x3FF) as usize + 1;
            let line = (ebx & 0xFFF) as usize + 1;
            ((eax >> 5) & 0x7, ways * partitions * line * (ecx as usize + 1))
        })
        .max()
        .map(|(_, size)| size)
}

/// A palette matrix as ((x_axis | y_axis), (z_axis | translation)).
pub(crate) type PackedAffine = [__m256; 2];

/// Packs a palette (O(joints), once per run).
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`Features::run_avx2_fma`]).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn pack_palette(palette: &[Affine3A]) -> Vec<PackedAffine> {
    palette
        .iter()
        .map(|m| {
            [
                _mm256_set_m128(m.matrix3.y_axis.into(), m.matrix3.x_axis.into()),
                _mm256_set_m128(m.translation.into(), m.matrix3.z_axis.into()),
            ]
        })
        .collect()
}

/// Linear blend of one chunk: v' = (Σ wᵢ·M(jᵢ))·v, n' = (Σ wᵢ·M(jᵢ))₃ₓ₃·n.
///
/// # Safety
/// The CPU must support AVX2 and FMA; every joint index must be in `palette` (validated).
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn linear_blend_chunk<const N: usize>(
    palette: &[PackedAffine],
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    let inputs = joints.iter().zip(weights).zip(positions.iter().zip(normals));
    for (((js, ws), (p, n)), (op, on)) in inputs.zip(out_positions.iter_mut().zip(out_normals.iter_mut())) {
        let m = &palette[js[0] as usize];
        let w = _mm256_set1_ps(ws[0]);
        let mut xy = _mm256_mul_ps(m[0], w);
        let mut zt = _mm256_mul_ps(m[1], w);
        for i in 1..N {
            let m = &palette[js[i] as usize];
            let w = _mm256_set1_ps(ws[i]);
            xy = _mm256_fmadd_ps(m[0], w, xy);
            zt = _mm256_fmadd_ps(m[1], w, zt);
        }
        let (x, y) = (_mm256_castps256_ps128(xy), _mm256_extractf128_ps::<1>(xy));
        let (z, t) = (_mm256_castps256_ps128(zt), _mm256_extractf128_ps::<1>(zt));
        let pos = _mm_fmadd_ps(
            x,
            _mm_set1_ps(p.x),
            _mm_fmadd_ps(y, _mm_set1_ps(p.y), _mm_fmadd_ps(z, _mm_set1_ps(p.z), t)),
        );
        let nrm = _mm_fmadd_ps(
            x,
            _mm_set1_ps(n.x),
            _mm_fmadd_ps(y, _mm_set1_ps(n.y), _mm_mul_ps(z, _mm_set1_ps(n.z))),
        );
        *op = Vec3A::from(pos).into();
        *on = Vec3A::from(nrm).into();
    }
}

/// A palette matrix as one 512-bit register [x_axis | y_axis | z_axis | translation] (the four
/// 16-byte columns of its `Affine3A`), 64-byte aligned.
pub(crate) type PackedAffine512 = __m512;

/// Packs a palette for [`linear_blend_chunk_avx512`] (O(joints), once per run).
///
/// # Safety
/// The CPU must support AVX-512F ([`Features::run_avx512vl`]).
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
pub(crate) unsafe fn pack_palette_avx512(palette: &[Affine3A]) -> Vec<PackedAffine512> {
    // SAFETY: an Affine3A is 16 floats (four Vec3A columns).
    palette.iter().map(|m| unsafe { _mm512_loadu_ps((m as *const Affine3A).cast::<f32>()) }).collect()
}

/// Σ wᵢ·M(jᵢ) of one vertex: N fused multiply-adds of whole 3×4 matrices.
///
/// # Safety
/// Every index in `js` must be in `palette`; the CPU must support AVX-512F.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
unsafe fn blend_avx512<const N: usize>(palette: &[PackedAffine512], js: &[u16; N], ws: &[f32; N]) -> __m512 {
    // SAFETY: the caller's contract.
    let m = |i: usize| unsafe { *palette.get_unchecked(js[i] as usize) };
    let mut blend = _mm512_mul_ps(m(0), _mm512_set1_ps(ws[0]));
    // An index loop: LLVM unrolls it, while an iterator's `skip(1)` stayed a call per step.
    #[allow(clippy::needless_range_loop)]
    for i in 1..N {
        blend = _mm512_fmadd_ps(m(i), _mm512_set1_ps(ws[i]), blend);
    }
    blend
}

/// One vertex of [`linear_blend_chunk_avx512`] (the groups' remainders): the blended matrix
/// times (p, 1) and (n, 0), each product's four 128-bit lanes summed.
///
/// # Safety
/// `v` must be a vertex of every slice; its joints must be in `palette`; the CPU must support
/// AVX-512F and AVX-512VL.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
unsafe fn linear_blend_one_avx512<const N: usize>(
    palette: &[PackedAffine512],
    (joints, weights): (&[[u16; N]], &[[f32; N]]),
    (positions, normals): (*const f32, *const f32),
    (out_positions, out_normals): (*mut f32, *mut f32),
    v: usize,
) {
    // SAFETY (all): the caller's contract; the masked loads and stores touch the vertex's three
    // floats only.
    unsafe {
        let m = blend_avx512(palette, joints.get_unchecked(v), weights.get_unchecked(v));
        // Lane l of each 128-bit quarter q: coordinate q of the vertex (the fourth: 1 or 0).
        let spread = _mm512_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3);
        let p = _mm512_castps128_ps512(_mm_maskz_loadu_ps(0b0111, positions.add(3 * v)));
        let n = _mm512_castps128_ps512(_mm_maskz_loadu_ps(0b0111, normals.add(3 * v)));
        let p = _mm512_mask_permutexvar_ps(_mm512_set1_ps(1.0), 0x0FFF, spread, p);
        let n = _mm512_maskz_permutexvar_ps(0x0FFF, spread, n);
        let (pm, nm) = (_mm512_mul_ps(m, p), _mm512_mul_ps(m, n));
        // [pm₀ + pm₂, pm₁ + pm₃, nm₀ + nm₂, nm₁ + nm₃], then quarters 0 and 2 summed with 1 and 3.
        let s = _mm512_add_ps(
            _mm512_shuffle_f32x4::<0b01_00_01_00>(pm, nm),
            _mm512_shuffle_f32x4::<0b11_10_11_10>(pm, nm),
        );
        let s = _mm512_add_ps(s, _mm512_shuffle_f32x4::<0b10_11_00_01>(s, s));
        _mm_mask_storeu_ps(out_positions.add(3 * v), 0b0111, _mm512_castps512_ps128(s));
        _mm_mask_storeu_ps(out_normals.add(3 * v), 0b0111, _mm512_extractf32x4_ps::<2>(s));
    }
}

/// Linear blend of one chunk with 512-bit registers: v' = (Σ wᵢ·M(jᵢ))·v,
/// n' = (Σ wᵢ·M(jᵢ))₃ₓ₃·n, four vertices at a time. A palette matrix is one register, so
/// blending one influence is one FMA; the four blended matrices are transposed by their 128-bit
/// lanes into the x axes, y axes, z axes and translations of the four vertices, which meet
/// the four vertices' coordinates (spread from one 48-byte load by a permutation) in three
/// FMAs per output; one permutation packs each output's twelve floats for one store.
///
/// `stream`: write the outputs with non-temporal (streaming) stores, which skip reading each
/// output cache line before writing it and do not keep the outputs in the cache: for jobs
/// larger than the last-level cache ([`streams_outputs`]), whose outputs would be evicted
/// before anyone reads them anyway. Only when both outputs lie at the same offset modulo 16
/// bytes (as separately allocated `Vec`s and their chunks do); otherwise ordinary stores.
///
/// # Safety
/// The CPU must support AVX2, FMA, AVX-512F and AVX-512VL ([`Features::run_avx512vl`]); every joint
/// index must be in `palette` (validated); all slices have the same length.
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn linear_blend_chunk_avx512<const N: usize>(
    palette: &[PackedAffine512],
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
    stream: bool,
) {
    let n = positions.len();
    debug_assert!([joints.len(), weights.len(), normals.len(), out_positions.len(), out_normals.len()]
        .iter()
        .all(|&l| l == n));
    let inputs = (positions.as_ptr().cast::<f32>(), normals.as_ptr().cast::<f32>());
    let outputs = (out_positions.as_mut_ptr().cast::<f32>(), out_normals.as_mut_ptr().cast::<f32>());
    let (pp, np) = inputs;
    let (opp, onp) = outputs;
    let stream = stream && opp as usize % 16 == onp as usize % 16;
    let mut v = 0;
    if stream {
        // Single vertices until the outputs are 16-byte aligned (at most three: 12 bytes per
        // vertex step through the four 4-byte offsets).
        while v < n && !(opp.wrapping_add(3 * v) as usize).is_multiple_of(16) {
            // SAFETY: v < n; the caller's contract.
            unsafe { linear_blend_one_avx512(palette, (joints, weights), inputs, outputs, v) };
            v += 1;
        }
    }
    // Lanes of one output's quarters: x₀x₀x₀x₀ | x₁… from the vertices' twelve floats, and back.
    let coordinate = |c: i32| {
        _mm512_setr_epi32(
            c,
            c,
            c,
            c,
            c + 3,
            c + 3,
            c + 3,
            c + 3,
            c + 6,
            c + 6,
            c + 6,
            c + 6,
            c + 9,
            c + 9,
            c + 9,
            c + 9,
        )
    };
    let (ix, iy, iz) = (coordinate(0), coordinate(1), coordinate(2));
    let compact = _mm512_setr_epi32(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 15, 15, 15, 15);
    while v + 4 <= n {
        // SAFETY: vertices v..v + 4 are in every slice; their joints are in the palette.
        let [a, b, c, d] = std::array::from_fn(|k| unsafe {
            blend_avx512(palette, joints.get_unchecked(v + k), weights.get_unchecked(v + k))
        });
        // Transpose by 128-bit lanes: x = [x_a | x_b | x_c | x_d], and so on.
        let (ab_low, ab_high) =
            (_mm512_shuffle_f32x4::<0b01_00_01_00>(a, b), _mm512_shuffle_f32x4::<0b11_10_11_10>(a, b));
        let (cd_low, cd_high) =
            (_mm512_shuffle_f32x4::<0b01_00_01_00>(c, d), _mm512_shuffle_f32x4::<0b11_10_11_10>(c, d));
        let x = _mm512_shuffle_f32x4::<0b10_00_10_00>(ab_low, cd_low);
        let y = _mm512_shuffle_f32x4::<0b11_01_11_01>(ab_low, cd_low);
        let z = _mm512_shuffle_f32x4::<0b10_00_10_00>(ab_high, cd_high);
        let t = _mm512_shuffle_f32x4::<0b11_01_11_01>(ab_high, cd_high);
        // The four vertices' twelve floats: one 64-byte load while 16 floats remain in the
        // slices (a masked load stops the hardware prefetcher's stream on some CPUs), else a
        // masked one of twelve.
        // SAFETY: floats 3v..3v + 16 (or 3v + 12, masked) of the 3n.
        let (ps, ns) = unsafe {
            if v + 6 <= n {
                (_mm512_loadu_ps(pp.add(3 * v)), _mm512_loadu_ps(np.add(3 * v)))
            } else {
                (_mm512_maskz_loadu_ps(0x0FFF, pp.add(3 * v)), _mm512_maskz_loadu_ps(0x0FFF, np.add(3 * v)))
            }
        };
        let spread = |xs: __m512, i: __m512i| _mm512_permutexvar_ps(i, xs);
        let pos = _mm512_fmadd_ps(
            x,
            spread(ps, ix),
            _mm512_fmadd_ps(y, spread(ps, iy), _mm512_fmadd_ps(z, spread(ps, iz), t)),
        );
        let nrm = _mm512_fmadd_ps(
            x,
            spread(ns, ix),
            _mm512_fmadd_ps(y, spread(ns, iy), _mm512_mul_ps(z, spread(ns, iz))),
        );
        let (pos, nrm) = (_mm512_permutexvar_ps(compact, pos), _mm512_permutexvar_ps(compact, nrm));
        // SAFETY: floats 3v..3v + 12 of the outputs; 16-byte aligned when streaming.
        unsafe {
            let (po, no) = (opp.add(3 * v), onp.add(3 * v));
            if stream {
                _mm_stream_ps(po, _mm512_castps512_ps128(pos));
                _mm_stream_ps(po.add(4), _mm512_extractf32x4_ps::<1>(pos));
                _mm_stream_ps(po.add(8), _mm512_extractf32x4_ps::<2>(pos));
                _mm_stream_ps(no, _mm512_castps512_ps128(nrm));
                _mm_stream_ps(no.add(4), _mm512_extractf32x4_ps::<1>(nrm));
                _mm_stream_ps(no.add(8), _mm512_extractf32x4_ps::<2>(nrm));
            } else {
                _mm512_mask_storeu_ps(po, 0x0FFF, pos);
                _mm512_mask_storeu_ps(no, 0x0FFF, nrm);
            }
        }
        v += 4;
    }
    while v < n {
        // SAFETY: v < n; the caller's contract.
        unsafe { linear_blend_one_avx512(palette, (joints, weights), inputs, outputs, v) };
        v += 1;
    }
    if stream {
        // Streaming stores are weakly ordered: make them visible before the chunk is reported
        // done (to another thread, through the chunk counter's release store).
        _mm_sfence();
    }
}

/// A dual quaternion as one register (real | dual).
pub(crate) type PackedDualQuat = __m256;

/// # Safety
/// The CPU must support AVX2 and FMA ([`Features::run_avx2_fma`]).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn pack_dual_quaternions(dqs: &[DualQuat]) -> Vec<PackedDualQuat> {
    dqs.iter().map(|q| _mm256_set_m128(Vec4::from(q.dual).into(), Vec4::from(q.real).into())).collect()
}

/// Dual quaternion blend of one chunk (see `dual_quaternion.rs` for the formula).
///
/// # Safety
/// The CPU must support AVX2 and FMA; every joint index must be in `dqs` (validated).
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn dual_quaternion_chunk<const N: usize>(
    dqs: &[PackedDualQuat],
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    let inputs = joints.iter().zip(weights).zip(positions.iter().zip(normals));
    for (((js, ws), (p, n)), (op, on)) in inputs.zip(out_positions.iter_mut().zip(out_normals.iter_mut())) {
        // Pivot: the real part of the largest-weight influence (first on ties).
        let mut pivot = _mm256_castps256_ps128(dqs[js[0] as usize]);
        let mut best = ws[0];
        for i in 1..N {
            let larger = ws[i] > best;
            best = if larger { ws[i] } else { best };
            let mask = _mm_castsi128_ps(_mm_set1_epi32(-(larger as i32)));
            pivot = _mm_blendv_ps(pivot, _mm256_castps256_ps128(dqs[js[i] as usize]), mask);
        }
        let sign_bit = _mm256_set1_ps(-0.0);
        let mut blend = _mm256_setzero_ps();
        for i in 0..N {
            let q = dqs[js[i] as usize];
            // dot(real, pivot) in every lane, then its sign onto the weight.
            let d = _mm_dp_ps::<0xFF>(_mm256_castps256_ps128(q), pivot);
            let sign = _mm256_and_ps(_mm256_set_m128(d, d), sign_bit);
            let w = _mm256_xor_ps(_mm256_set1_ps(ws[i]), sign);
            blend = _mm256_fmadd_ps(q, w, blend);
        }
        let real = _mm256_castps256_ps128(blend);
        let dual = _mm256_extractf128_ps::<1>(blend);
        // 1/|real| by rsqrt and one Newton step (relative error ~1e-7).
        let len2 = _mm_dp_ps::<0xFF>(real, real);
        let r0 = _mm_rsqrt_ps(len2);
        let inv = _mm_mul_ps(
            _mm_mul_ps(_mm_set1_ps(0.5), r0),
            _mm_fnmadd_ps(_mm_mul_ps(len2, r0), r0, _mm_set1_ps(3.0)),
        );
        let real = Vec4::from(_mm_mul_ps(real, inv));
        let dual = Vec4::from(_mm_mul_ps(dual, inv));
        let r = Vec3A::from_vec4(real);
        let d = Vec3A::from_vec4(dual);
        let (rw, dw) = (real.w, dual.w);
        let p = Vec3A::from(*p);
        let n = Vec3A::from(*n);
        let translation = 2.0 * (rw * d - dw * r + r.cross(d));
        *op = (p + 2.0 * r.cross(r.cross(p) + rw * p) + translation).into();
        *on = (n + 2.0 * r.cross(r.cross(n) + rw * n)).into();
    }
}

/// A joint's bones-blending terms B₀, B₁, B₂ (packed like the palette) and θ/2.
pub(crate) struct PackedBonesBlend {
    terms: [PackedAffine; 3],
    half_angle: f32,
}

/// # Safety
/// The CPU must support AVX2 and FMA ([`Features::run_avx2_fma`]).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn pack_bones_blending(joints: &[BonesBlendJoint]) -> Vec<PackedBonesBlend> {
    joints
        .iter()
        .map(|k| PackedBonesBlend {
            terms: k.blend_terms.map(|m| {
                [
                    _mm256_set_m128(m.matrix3.y_axis.into(), m.matrix3.x_axis.into()),
                    _mm256_set_m128(m.translation.into(), m.matrix3.z_axis.into()),
                ]
            }),
            half_angle: k.half_angle,
        })
        .collect()
}

/// Bones blending of one chunk: v' = (B₀ + sin φ·B₁ + (1 − cos φ)·B₂)·v, φ = t·θ.
///
/// # Safety
/// The CPU must support AVX2 and FMA; every joint index must be in `joints` (validated).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn bones_blending_chunk(
    joints: &[PackedBonesBlend],
    bindings: &[BonesBlendVertex],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    // φ/2 = t·θ/2 for 8 vertices at a time: sin φ = 2·s·c and 1 − cos φ = 2·s² by the same
    // polynomials as the portable path, in 256-bit lanes.
    let mut sin = [0.0f32; 8];
    let mut versin = [0.0f32; 8];
    for start in (0..bindings.len()).step_by(8) {
        let end = (start + 8).min(bindings.len());
        let count = end - start;
        if count == 8 {
            let b = &bindings[start..end];
            let f = |l: usize| b[l].t * joints[b[l].joint as usize].half_angle;
            let x = _mm256_setr_ps(f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7));
            let (s, c) = sin_cos_quarter_turn_x8(x);
            let two = _mm256_set1_ps(2.0);
            _mm256_storeu_ps(sin.as_mut_ptr(), _mm256_mul_ps(two, _mm256_mul_ps(s, c)));
            _mm256_storeu_ps(versin.as_mut_ptr(), _mm256_mul_ps(two, _mm256_mul_ps(s, s)));
        } else {
            for l in 0..count {
                let b = &bindings[start + l];
                let (s, c) = sin_cos_quarter_turn(b.t * joints[b.joint as usize].half_angle);
                sin[l] = 2.0 * s * c;
                versin[l] = 2.0 * s * s;
            }
        }
        for l in 0..count {
            let v = start + l;
            let (p, n) = (positions[v], normals[v]);
            let k = &joints[bindings[v].joint as usize];
            let sin = _mm256_set1_ps(sin[l]);
            let versin = _mm256_set1_ps(versin[l]);
            let [b0, b1, b2] = &k.terms;
            let xy = _mm256_fmadd_ps(b2[0], versin, _mm256_fmadd_ps(b1[0], sin, b0[0]));
            let zt = _mm256_fmadd_ps(b2[1], versin, _mm256_fmadd_ps(b1[1], sin, b0[1]));
            let (x, y) = (_mm256_castps256_ps128(xy), _mm256_extractf128_ps::<1>(xy));
            let (z, t) = (_mm256_castps256_ps128(zt), _mm256_extractf128_ps::<1>(zt));
            let pos = _mm_fmadd_ps(
                x,
                _mm_set1_ps(p.x),
                _mm_fmadd_ps(y, _mm_set1_ps(p.y), _mm_fmadd_ps(z, _mm_set1_ps(p.z), t)),
            );
            let nrm = _mm_fmadd_ps(
                x,
                _mm_set1_ps(n.x),
                _mm_fmadd_ps(y, _mm_set1_ps(n.y), _mm_mul_ps(z, _mm_set1_ps(n.z))),
            );
            out_positions[v] = Vec3A::from(pos).into();
            out_normals[v] = Vec3A::from(nrm).into();
        }
    }
}

/// [`sin_cos_quarter_turn`] in 8 lanes (the same Taylor polynomials, evaluated by Horner's rule
/// with fused multiply-adds).
#[inline]
#[target_feature(enable = "avx2,fma")]
fn sin_cos_quarter_turn_x8(x: __m256) -> (__m256, __m256) {
    let x2 = _mm256_mul_ps(x, x);
    let horner = |coefficients: &[f32]| {
        let mut acc = _mm256_set1_ps(coefficients[0]);
        for &c in &coefficients[1..] {
            acc = _mm256_fmadd_ps(acc, x2, _mm256_set1_ps(c));
        }
        acc
    };
    let s = _mm256_mul_ps(
        x,
        horner(&[-1.0 / 39_916_800.0, 1.0 / 362_880.0, -1.0 / 5040.0, 1.0 / 120.0, -1.0 / 6.0, 1.0]),
    );
    let c = horner(&[
        1.0 / 479_001_600.0,
        -1.0 / 3_628_800.0,
        1.0 / 40_320.0,
        -1.0 / 720.0,
        1.0 / 24.0,
        -0.5,
        1.0,
    ]);
    (s, c)
}

/// Which of three consecutive registers (floats 0..8, 8..16, 16..24 of 8 interleaved Vec3s)
/// holds component `c` in lane `k`: float 8r + k is component (8r + k) % 3, so r = 2·(c − k)
/// mod 3 (8 ≡ 2 and 2·2 ≡ 1 mod 3).
const fn register_of(c: i32, k: i32) -> i32 {
    (2 * (c - k)).rem_euclid(3)
}

/// Blend mask: the lanes k where component `c` is in register `r`.
const fn lanes_in(c: i32, r: i32) -> i32 {
    let mut mask = 0;
    let mut k = 0;
    while k < 8 {
        if register_of(c, k) == r {
            mask |= 1 << k;
        }
        k += 1;
    }
    mask
}

/// Blend mask for output register `r`: the lanes k that hold component `c`.
const fn lanes_of(r: i32, c: i32) -> i32 {
    let mut mask = 0;
    let mut k = 0;
    while k < 8 {
        if (8 * r + k) % 3 == c {
            mask |= 1 << k;
        }
        k += 1;
    }
    mask
}

/// Permutation for [`load_deinterleaved`]: lane l of component c takes lane (3l + c) mod 8
/// (the low three bits: `_mm256_permutevar8x32_ps` reads no others).
const fn load_order(c: i32) -> [i32; 8] {
    let mut order = [0; 8];
    let mut l = 0;
    while l < 8 {
        order[l as usize] = (3 * l + c) & 7;
        l += 1;
    }
    order
}

/// Permutation for [`store_interleaved`]: lane k of component c takes the vertex whose
/// component lands in lane k of its output register.
const fn store_order(c: i32) -> [i32; 8] {
    let mut order = [0; 8];
    let mut k = 0;
    while k < 8 {
        order[k as usize] = (8 * register_of(c, k) + k) / 3;
        k += 1;
    }
    order
}

const LOAD_ORDER: [[i32; 8]; 3] = [load_order(0), load_order(1), load_order(2)];
const STORE_ORDER: [[i32; 8]; 3] = [store_order(0), store_order(1), store_order(2)];

/// An index register from a table.
#[inline]
#[target_feature(enable = "avx2,fma")]
fn indices(table: &[i32; 8]) -> __m256i {
    // SAFETY: 8 i32s.
    unsafe { _mm256_loadu_si256(table.as_ptr().cast::<__m256i>()) }
}

/// Reads 8 interleaved Vec3s (24 floats x₀y₀z₀x₁… at `at`) as x, y and z registers: per
/// component, two blends gather the lanes that hold it, one permutation puts them in order.
///
/// # Safety
/// `at` must be valid for reading 24 floats; the CPU must support AVX2.
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn load_deinterleaved(at: *const f32) -> [__m256; 3] {
    // SAFETY: floats 0..24 of the caller's 24.
    let (v0, v1, v2) =
        unsafe { (_mm256_loadu_ps(at), _mm256_loadu_ps(at.add(8)), _mm256_loadu_ps(at.add(16))) };
    let x = _mm256_blend_ps::<{ lanes_in(0, 2) }>(_mm256_blend_ps::<{ lanes_in(0, 1) }>(v0, v1), v2);
    let y = _mm256_blend_ps::<{ lanes_in(1, 2) }>(_mm256_blend_ps::<{ lanes_in(1, 1) }>(v0, v1), v2);
    let z = _mm256_blend_ps::<{ lanes_in(2, 2) }>(_mm256_blend_ps::<{ lanes_in(2, 1) }>(v0, v1), v2);
    [
        _mm256_permutevar8x32_ps(x, indices(&LOAD_ORDER[0])),
        _mm256_permutevar8x32_ps(y, indices(&LOAD_ORDER[1])),
        _mm256_permutevar8x32_ps(z, indices(&LOAD_ORDER[2])),
    ]
}

/// Writes 8 vertices given as x, y and z registers to 24 floats x₀y₀z₀x₁… at `out` (the
/// inverse of [`load_deinterleaved`]: one permutation per component, two blends per register).
///
/// # Safety
/// `out` must be valid for writing 24 floats; the CPU must support AVX2.
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn store_interleaved(out: *mut f32, x: __m256, y: __m256, z: __m256) {
    // Lane k of the permuted component c is that component of the vertex whose float lands in
    // lane k of its output register.
    let xs = _mm256_permutevar8x32_ps(x, indices(&STORE_ORDER[0]));
    let ys = _mm256_permutevar8x32_ps(y, indices(&STORE_ORDER[1]));
    let zs = _mm256_permutevar8x32_ps(z, indices(&STORE_ORDER[2]));
    let r0 = _mm256_blend_ps::<{ lanes_of(0, 2) }>(_mm256_blend_ps::<{ lanes_of(0, 1) }>(xs, ys), zs);
    let r1 = _mm256_blend_ps::<{ lanes_of(1, 2) }>(_mm256_blend_ps::<{ lanes_of(1, 1) }>(xs, ys), zs);
    let r2 = _mm256_blend_ps::<{ lanes_of(2, 2) }>(_mm256_blend_ps::<{ lanes_of(2, 1) }>(xs, ys), zs);
    // SAFETY: floats 0..24 of the caller's 24.
    unsafe {
        _mm256_storeu_ps(out, r0);
        _mm256_storeu_ps(out.add(8), r1);
        _mm256_storeu_ps(out.add(16), r2);
    }
}

/// The weights of 8 vertices, one register per influence. N = 4: rows l and l + 4 share a
/// register (one 128-bit half each) and a 4×4 transpose in each half puts them in order;
/// N = 8: one 8×8 transpose; otherwise gathers.
///
/// # Safety
/// `ws` must hold 8 rows; the CPU must support AVX2 and FMA.
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn weights_soa<const N: usize>(ws: &[[f32; N]]) -> [__m256; N] {
    debug_assert_eq!(ws.len(), 8);
    let at = ws.as_ptr().cast::<f32>();
    let mut out = [_mm256_setzero_ps(); N];
    if N == 4 {
        // SAFETY: row l is floats 4l..4l + 4 of the 32.
        let (r0, r1, r2, r3) = unsafe {
            (
                _mm256_loadu2_m128(at.add(16), at),
                _mm256_loadu2_m128(at.add(20), at.add(4)),
                _mm256_loadu2_m128(at.add(24), at.add(8)),
                _mm256_loadu2_m128(at.add(28), at.add(12)),
            )
        };
        let t0 = _mm256_unpacklo_ps(r0, r1);
        let t1 = _mm256_unpackhi_ps(r0, r1);
        let t2 = _mm256_unpacklo_ps(r2, r3);
        let t3 = _mm256_unpackhi_ps(r2, r3);
        out[0] = _mm256_shuffle_ps::<0x44>(t0, t2);
        out[1] = _mm256_shuffle_ps::<0xEE>(t0, t2);
        out[2] = _mm256_shuffle_ps::<0x44>(t1, t3);
        out[3] = _mm256_shuffle_ps::<0xEE>(t1, t3);
    } else if N == 8 {
        // SAFETY: row l is floats 8l..8l + 8 of the 64.
        let t = transpose8(std::array::from_fn(|l| unsafe { _mm256_loadu_ps(at.add(8 * l)) }));
        out.copy_from_slice(&t[..N]);
    } else {
        let n = N as i32;
        let stride_n = _mm256_setr_epi32(0, n, 2 * n, 3 * n, 4 * n, 5 * n, 6 * n, 7 * n);
        for (i, w) in out.iter_mut().enumerate() {
            // SAFETY: lane l reads ws[l][i], inside the 8·N floats of `ws`.
            *w = unsafe { _mm256_i32gather_ps::<4>(at.add(i), stride_n) };
        }
    }
    out
}

/// Transposes 8 rows of 8 floats (row l = lane l's dual quaternion) into 8 columns
/// (column c = component c of every lane).
#[inline]
#[target_feature(enable = "avx2,fma")]
fn transpose8(r: [__m256; 8]) -> [__m256; 8] {
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    let t4 = _mm256_unpacklo_ps(r[4], r[5]);
    let t5 = _mm256_unpackhi_ps(r[4], r[5]);
    let t6 = _mm256_unpacklo_ps(r[6], r[7]);
    let t7 = _mm256_unpackhi_ps(r[6], r[7]);
    let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
    let u1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
    let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
    let u3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
    let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
    let u5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
    let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
    let u7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
    [
        _mm256_permute2f128_ps::<0x20>(u0, u4),
        _mm256_permute2f128_ps::<0x20>(u1, u5),
        _mm256_permute2f128_ps::<0x20>(u2, u6),
        _mm256_permute2f128_ps::<0x20>(u3, u7),
        _mm256_permute2f128_ps::<0x31>(u0, u4),
        _mm256_permute2f128_ps::<0x31>(u1, u5),
        _mm256_permute2f128_ps::<0x31>(u2, u6),
        _mm256_permute2f128_ps::<0x31>(u3, u7),
    ]
}

/// Two 4×4 transposes, one per 128-bit half: row l of each half becomes column l.
#[inline]
#[target_feature(enable = "avx2,fma")]
fn transpose4x2([r0, r1, r2, r3]: [__m256; 4]) -> [__m256; 4] {
    let t0 = _mm256_unpacklo_ps(r0, r1);
    let t1 = _mm256_unpackhi_ps(r0, r1);
    let t2 = _mm256_unpacklo_ps(r2, r3);
    let t3 = _mm256_unpackhi_ps(r2, r3);
    [
        _mm256_shuffle_ps::<0x44>(t0, t2),
        _mm256_shuffle_ps::<0xEE>(t0, t2),
        _mm256_shuffle_ps::<0x44>(t1, t3),
        _mm256_shuffle_ps::<0xEE>(t1, t3),
    ]
}

/// Floats OFFSET..OFFSET + 4 (0: the real part, 4: the dual part) of `dqs[joints[l]]` in SoA
/// form (x, y, z, w of the 8 lanes).
///
/// # Safety
/// Every index must be in `dqs`; the CPU must support AVX2 and FMA.
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn parts_soa<const OFFSET: usize>(entries: &[*const f32; 8]) -> [__m256; 4] {
    // SAFETY: four floats inside palette entries.
    let at = |l: usize| unsafe { entries[l].add(OFFSET) };
    // SAFETY: as above.
    unsafe {
        transpose4x2([
            _mm256_loadu2_m128(at(4), at(0)),
            _mm256_loadu2_m128(at(5), at(1)),
            _mm256_loadu2_m128(at(6), at(2)),
            _mm256_loadu2_m128(at(7), at(3)),
        ])
    }
}

/// m0·x + m1·y + m2·z + t, 8 lanes.
#[inline]
#[target_feature(enable = "avx2,fma")]
fn row(m0: __m256, m1: __m256, m2: __m256, [x, y, z]: [__m256; 3], t: __m256) -> __m256 {
    _mm256_fmadd_ps(m0, x, _mm256_fmadd_ps(m1, y, _mm256_fmadd_ps(m2, z, t)))
}

/// Defines a dual quaternion chunk kernel with the given target features. The same body is
/// compiled twice: for AVX2 + FMA, and for AVX2 + FMA + AVX-512VL, where the 32 vector registers
/// (ymm0–ymm31) hold the kernel's ~25 live values without spilling them to the stack. Spills
/// matter here beyond their own cost: every step stores them and then loads palette entries
/// from fixed addresses, and when a spill slot and a palette entry share their address bits
/// 11..0 ("4K aliasing") the load waits for the store. Which entries alias depends on where the
/// stack happens to lie (randomized per process), so the AVX2 kernel's time is bimodal across
/// runs; see docs/benchmarks.md, skinning section.
macro_rules! dual_quaternion_kernel {
    ($(#[$attr:meta])* $name:ident) => {
        /// Dual quaternion skinning of one chunk, 8 vertices at a time in structure-of-arrays
        /// form (each register holds one component of 8 vertices), the remainder one at a time
        /// with [`dual_quaternion_chunk`]. Same sign rule; the blended dual quaternion (r, d)
        /// becomes a rigid 3×4 matrix once per vertex, without normalizing it first: with
        /// s = 2/|r|², R = I + s·[−(y²+z²), xy−wz, xz+wy; xy+wz, −(x²+z²), yz−wx;
        /// xz−wy, yz+wx, −(x²+y²)] and t = s·(w_r·d⃗ − w_d·r⃗ + r⃗ × d⃗), which equal the
        /// normalized formulas.
        ///
        /// # Safety
        /// The CPU must support the target features named above; every joint index must be in
        /// `dqs` (validated).
        $(#[$attr])*
        #[allow(clippy::too_many_arguments)]
        pub(crate) unsafe fn $name<const N: usize>(
            dqs: &[PackedDualQuat],
            joints: &[[u16; N]],
            weights: &[[f32; N]],
            positions: &[Vec3],
            normals: &[Vec3],
            out_positions: &mut [Vec3],
            out_normals: &mut [Vec3],
        ) {
            let full = out_positions.len() / 8 * 8;
            let sign_bit = _mm256_set1_ps(-0.0);
            for base in (0..full).step_by(8) {
                let js = &joints[base..base + 8];
                // SAFETY: 8 rows of weights.
                let wv = unsafe { weights_soa::<N>(&weights[base..base + 8]) };
                // Each influence's real parts in SoA form, and the pivot: the real part of each
                // lane's largest-weight influence (first on ties).
                let mut reals = [[_mm256_setzero_ps(); 4]; N];
                let mut pivot = [_mm256_setzero_ps(); 4];
                let mut best = wv[0];
                let mut entries = [[std::ptr::null::<f32>(); 8]; N];
                for (i, ((r, &w), e)) in reals.iter_mut().zip(&wv).zip(&mut entries).enumerate() {
                    for (e, vertex) in e.iter_mut().zip(js) {
                        // SAFETY: every index is in `dqs` (validated).
                        *e = unsafe { dqs.as_ptr().add(vertex[i] as usize).cast::<f32>() };
                    }
                    // SAFETY: palette entries.
                    *r = unsafe { parts_soa::<0>(e) };
                    let larger = _mm256_cmp_ps::<_CMP_GT_OQ>(w, best);
                    best = _mm256_blendv_ps(best, w, larger);
                    for c in 0..4 {
                        pivot[c] = if i == 0 { r[c] } else { _mm256_blendv_ps(pivot[c], r[c], larger) };
                    }
                }
                // Blend, one influence at a time in SoA form.
                let mut q = [_mm256_setzero_ps(); 8];
                for ((r, &w), e) in reals.iter().zip(&wv).zip(&entries) {
                    // SAFETY: as above.
                    let d = unsafe { parts_soa::<4>(e) };
                    let dot = _mm256_fmadd_ps(
                        r[3],
                        pivot[3],
                        _mm256_fmadd_ps(
                            r[2],
                            pivot[2],
                            _mm256_fmadd_ps(r[1], pivot[1], _mm256_mul_ps(r[0], pivot[0])),
                        ),
                    );
                    let w = _mm256_xor_ps(w, _mm256_and_ps(dot, sign_bit));
                    for c in 0..4 {
                        q[c] = _mm256_fmadd_ps(r[c], w, q[c]);
                        q[c + 4] = _mm256_fmadd_ps(d[c], w, q[c + 4]);
                    }
                }
                let [rx, ry, rz, rw, dx, dy, dz, dw] = q;
                // s = 2/|r|² (one division for 8 vertices).
                let len2 = _mm256_fmadd_ps(
                    rw,
                    rw,
                    _mm256_fmadd_ps(rz, rz, _mm256_fmadd_ps(ry, ry, _mm256_mul_ps(rx, rx))),
                );
                let s = _mm256_div_ps(_mm256_set1_ps(2.0), len2);
                let (sx, sy, sz) = (_mm256_mul_ps(s, rx), _mm256_mul_ps(s, ry), _mm256_mul_ps(s, rz));
                let (xx, yy, zz) = (_mm256_mul_ps(sx, rx), _mm256_mul_ps(sy, ry), _mm256_mul_ps(sz, rz));
                let (xy, xz, yz) = (_mm256_mul_ps(sx, ry), _mm256_mul_ps(sx, rz), _mm256_mul_ps(sy, rz));
                let (wx, wy, wz) = (_mm256_mul_ps(sx, rw), _mm256_mul_ps(sy, rw), _mm256_mul_ps(sz, rw));
                let one = _mm256_set1_ps(1.0);
                // Rows of R.
                let m00 = _mm256_sub_ps(one, _mm256_add_ps(yy, zz));
                let m01 = _mm256_sub_ps(xy, wz);
                let m02 = _mm256_add_ps(xz, wy);
                let m10 = _mm256_add_ps(xy, wz);
                let m11 = _mm256_sub_ps(one, _mm256_add_ps(xx, zz));
                let m12 = _mm256_sub_ps(yz, wx);
                let m20 = _mm256_sub_ps(xz, wy);
                let m21 = _mm256_add_ps(yz, wx);
                let m22 = _mm256_sub_ps(one, _mm256_add_ps(xx, yy));
                // t = s·(w_r·d⃗ − w_d·r⃗ + r⃗ × d⃗).
                let cross = |a: __m256, b: __m256, c: __m256, e: __m256| _mm256_fmsub_ps(a, b, _mm256_mul_ps(c, e));
                let tx = _mm256_mul_ps(s, _mm256_fmadd_ps(rw, dx, _mm256_fnmadd_ps(dw, rx, cross(ry, dz, rz, dy))));
                let ty = _mm256_mul_ps(s, _mm256_fmadd_ps(rw, dy, _mm256_fnmadd_ps(dw, ry, cross(rz, dx, rx, dz))));
                let tz = _mm256_mul_ps(s, _mm256_fmadd_ps(rw, dz, _mm256_fnmadd_ps(dw, rz, cross(rx, dy, ry, dx))));
                // SAFETY (all four): 8 Vec3s are 24 contiguous floats of their slices.
                let p = unsafe { load_deinterleaved(positions[base..base + 8].as_ptr().cast::<f32>()) };
                let n = unsafe { load_deinterleaved(normals[base..base + 8].as_ptr().cast::<f32>()) };
                let (px, py, pz) =
                    (row(m00, m01, m02, p, tx), row(m10, m11, m12, p, ty), row(m20, m21, m22, p, tz));
                let zero = _mm256_setzero_ps();
                let (nx, ny, nz) =
                    (row(m00, m01, m02, n, zero), row(m10, m11, m12, n, zero), row(m20, m21, m22, n, zero));
                unsafe {
                    store_interleaved(out_positions[base..base + 8].as_mut_ptr().cast::<f32>(), px, py, pz);
                    store_interleaved(out_normals[base..base + 8].as_mut_ptr().cast::<f32>(), nx, ny, nz);
                }
            }
            dual_quaternion_chunk(
                dqs,
                &joints[full..],
                &weights[full..],
                &positions[full..],
                &normals[full..],
                &mut out_positions[full..],
                &mut out_normals[full..],
            );
        }
    };
}

dual_quaternion_kernel!(
    #[target_feature(enable = "avx2,fma")]
    dual_quaternion_chunk_soa
);
dual_quaternion_kernel!(
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
    dual_quaternion_chunk_soa_avx512
);

/// Four floats at each of 16 addresses (lane l's row at `rows[l]`) in structure-of-arrays
/// form: register c holds float c of every row, in lane order. Each register is first filled
/// with the rows k, k + 4, k + 8 and k + 12 (one per 128-bit lane, by inserts from memory),
/// then a 4×4 transpose inside each 128-bit lane puts lane 4q + k's float c at lane 4q + k.
///
/// # Safety
/// Every address must be valid for reading 4 floats; the CPU must support AVX-512F.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
unsafe fn rows4_soa16(rows: &[*const f32; 16]) -> [__m512; 4] {
    // SAFETY: the caller's contract.
    let row = |l: usize| unsafe { _mm_loadu_ps(rows[l]) };
    let quarters = |k: usize| {
        let r = _mm512_castps128_ps512(row(k));
        let r = _mm512_insertf32x4::<1>(r, row(k + 4));
        let r = _mm512_insertf32x4::<2>(r, row(k + 8));
        _mm512_insertf32x4::<3>(r, row(k + 12))
    };
    transpose4_in_lanes([quarters(0), quarters(1), quarters(2), quarters(3)])
}

/// A 4×4 transpose inside each 128-bit lane of four registers.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
fn transpose4_in_lanes([r0, r1, r2, r3]: [__m512; 4]) -> [__m512; 4] {
    let t0 = _mm512_unpacklo_ps(r0, r1);
    let t1 = _mm512_unpackhi_ps(r0, r1);
    let t2 = _mm512_unpacklo_ps(r2, r3);
    let t3 = _mm512_unpackhi_ps(r2, r3);
    [
        _mm512_shuffle_ps::<0x44>(t0, t2),
        _mm512_shuffle_ps::<0xEE>(t0, t2),
        _mm512_shuffle_ps::<0x44>(t1, t3),
        _mm512_shuffle_ps::<0xEE>(t1, t3),
    ]
}

/// Influence `i`'s dual quaternions of 16 vertices in structure-of-arrays form: real x, y, z,
/// w, then dual x, y, z, w, each register in vertex order. Each 32-byte palette entry is one
/// load; two entries share a register (vertices k and k + 4, or k + 8 and k + 12), a 4×4
/// transpose inside each 128-bit lane of four such registers gathers one component of four
/// vertices per lane, and a shuffle of 128-bit lanes puts them in vertex order.
///
/// # Safety
/// `joints` must hold 16 rows whose index `i` is in `dqs`; the CPU must support AVX-512F.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
unsafe fn dual_quaternions_soa16<const N: usize>(
    dqs: &[PackedDualQuat],
    joints: &[[u16; N]],
    i: usize,
) -> [__m512; 8] {
    // SAFETY: the caller's contract.
    let entry = |l: usize| unsafe { *dqs.get_unchecked(joints.get_unchecked(l)[i] as usize) };
    let pair = |a: usize, b: usize| {
        let low = _mm512_castpd256_pd512(_mm256_castps_pd(entry(a)));
        _mm512_castpd_ps(_mm512_insertf64x4::<1>(low, _mm256_castps_pd(entry(b))))
    };
    // t[c]: lanes 0 and 2 hold component c of the real parts of vertices 0..4 and 4..8, lanes 1
    // and 3 of their dual parts; u[c] the same for vertices 8..16.
    let t = transpose4_in_lanes([pair(0, 4), pair(1, 5), pair(2, 6), pair(3, 7)]);
    let u = transpose4_in_lanes([pair(8, 12), pair(9, 13), pair(10, 14), pair(11, 15)]);
    let mut out = [_mm512_setzero_ps(); 8];
    for c in 0..4 {
        out[c] = _mm512_shuffle_f32x4::<0b10_00_10_00>(t[c], u[c]);
        out[c + 4] = _mm512_shuffle_f32x4::<0b11_01_11_01>(t[c], u[c]);
    }
    out
}

/// Permutation indices for [`load_deinterleaved16`]: lane l of component c is float 3l + c
/// of the 48, taken from the first two registers (index < 32) or, `third`, from the third.
const fn deinterleave16_order(c: i32, third: bool) -> [i32; 16] {
    let mut order = [0; 16];
    let mut l = 0;
    while l < 16 {
        let f = 3 * l + c;
        // Float f of the third register is its lane f − 32, and f − 32 ≡ f (mod 16).
        order[l as usize] = if third { f & 15 } else { f & 31 };
        l += 1;
    }
    order
}

/// The lanes of component `c` that come from the third register.
const fn deinterleave16_third(c: i32) -> u16 {
    let mut mask = 0;
    let mut l = 0;
    while l < 16 {
        if 3 * l + c >= 32 {
            mask |= 1 << l;
        }
        l += 1;
    }
    mask
}

/// Permutation indices for [`store_interleaved16`]: float 16r + k of the output is component
/// (16r + k) mod 3 of vertex (16r + k) / 3, from x (index l) or y (16 + l), or, `from_z`, z.
const fn interleave16_order(r: i32, from_z: bool) -> [i32; 16] {
    let mut order = [0; 16];
    let mut k = 0;
    while k < 16 {
        let f = 16 * r + k;
        let (l, c) = (f / 3, f % 3);
        order[k as usize] = if from_z || c == 0 { l } else { 16 + l };
        k += 1;
    }
    order
}

/// The lanes of output register `r` that hold a z component.
const fn interleave16_z(r: i32) -> u16 {
    let mut mask = 0;
    let mut k = 0;
    while k < 16 {
        if (16 * r + k) % 3 == 2 {
            mask |= 1 << k;
        }
        k += 1;
    }
    mask
}

const DEINTERLEAVE16: [[[i32; 16]; 3]; 2] = [
    [deinterleave16_order(0, false), deinterleave16_order(1, false), deinterleave16_order(2, false)],
    [deinterleave16_order(0, true), deinterleave16_order(1, true), deinterleave16_order(2, true)],
];
const DEINTERLEAVE16_THIRD: [u16; 3] =
    [deinterleave16_third(0), deinterleave16_third(1), deinterleave16_third(2)];
const INTERLEAVE16: [[[i32; 16]; 3]; 2] = [
    [interleave16_order(0, false), interleave16_order(1, false), interleave16_order(2, false)],
    [interleave16_order(0, true), interleave16_order(1, true), interleave16_order(2, true)],
];
const INTERLEAVE16_Z: [u16; 3] = [interleave16_z(0), interleave16_z(1), interleave16_z(2)];

/// A 512-bit index register from a table.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
fn indices16(table: &[i32; 16]) -> __m512i {
    // SAFETY: 16 i32s.
    unsafe { _mm512_loadu_si512(table.as_ptr().cast()) }
}

/// Reads 16 interleaved Vec3s (48 floats x₀y₀z₀x₁… at `at`) as x, y and z registers: per
/// component, one two-register permutation and one masked permutation of the third.
///
/// # Safety
/// `at` must be valid for reading 48 floats; the CPU must support AVX-512F.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
unsafe fn load_deinterleaved16(at: *const f32) -> [__m512; 3] {
    // SAFETY: floats 0..48 of the caller's 48.
    let (v0, v1, v2) =
        unsafe { (_mm512_loadu_ps(at), _mm512_loadu_ps(at.add(16)), _mm512_loadu_ps(at.add(32))) };
    std::array::from_fn(|c| {
        let low = _mm512_permutex2var_ps(v0, indices16(&DEINTERLEAVE16[0][c]), v1);
        _mm512_mask_permutexvar_ps(low, DEINTERLEAVE16_THIRD[c], indices16(&DEINTERLEAVE16[1][c]), v2)
    })
}

/// Writes 16 vertices given as x, y and z registers to 48 floats x₀y₀z₀x₁… at `out` (the
/// inverse of [`load_deinterleaved16`]).
///
/// # Safety
/// `out` must be valid for writing 48 floats; the CPU must support AVX-512F.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
unsafe fn store_interleaved16(out: *mut f32, x: __m512, y: __m512, z: __m512, stream: bool) {
    for r in 0..3 {
        let xy = _mm512_permutex2var_ps(x, indices16(&INTERLEAVE16[0][r]), y);
        let xyz = _mm512_mask_permutexvar_ps(xy, INTERLEAVE16_Z[r], indices16(&INTERLEAVE16[1][r]), z);
        // SAFETY: floats 16r..16r + 16 of the caller's 48, 64-byte aligned when streaming.
        unsafe {
            if stream {
                _mm512_stream_ps(out.add(16 * r), xyz);
            } else {
                _mm512_storeu_ps(out.add(16 * r), xyz);
            }
        }
    }
}

/// m0·x + m1·y + m2·z + t, 16 lanes.
#[inline]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
fn row16(m0: __m512, m1: __m512, m2: __m512, [x, y, z]: [__m512; 3], t: __m512) -> __m512 {
    _mm512_fmadd_ps(m0, x, _mm512_fmadd_ps(m1, y, _mm512_fmadd_ps(m2, z, t)))
}

/// Dual quaternion skinning of one chunk with 512-bit registers, 16 vertices at a time in
/// structure-of-arrays form: the same steps and formulas as the 8-lane kernels
/// ([`dual_quaternion_chunk_soa_avx512`], which also does the remainder, and every N that is
/// not a multiple of 4), with each palette entry loaded whole (32 bytes) and transposed by
/// [`dual_quaternions_soa16`].
///
/// `stream`: write the outputs with 64-byte streaming stores, for jobs larger than the
/// last-level cache ([`streams_outputs`], as linear blend does): a group of 16 vertices is 192
/// bytes per output, three whole cache lines once the outputs are 64-byte aligned, so the
/// interleaved registers are stored as they are (the vertices before the first line boundary,
/// at most 15, go to the 8-lane kernel). Only when both outputs lie at the same offset modulo
/// 64 bytes (as separately allocated large `Vec`s and their chunks do); otherwise ordinary
/// stores.
///
/// # Safety
/// The CPU must support AVX2, FMA, AVX-512F and AVX-512VL ([`Features::run_avx512vl`]); every joint
/// index must be in `dqs` (validated); all slices have the same length.
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn dual_quaternion_chunk_avx512_x16<const N: usize>(
    dqs: &[PackedDualQuat],
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
    stream: bool,
) {
    let n = out_positions.len();
    let (opp, onp) = (out_positions.as_mut_ptr() as usize, out_normals.as_mut_ptr() as usize);
    // Streaming: 64-byte stores of whole cache lines, from the first vertex whose outputs start
    // a line (at most 15 vertices in: 12 bytes per vertex step through every 4-byte offset
    // modulo 64), when both outputs lie at the same offset modulo 64.
    let stream = stream && N.is_multiple_of(4) && opp % 64 == onp % 64;
    let head =
        if stream { (0..16).find(|k| (opp + 12 * k).is_multiple_of(64)).unwrap_or(n).min(n) } else { 0 };
    if head > 0 {
        // SAFETY: the caller's contract (the same CPU features).
        unsafe {
            dual_quaternion_chunk_soa_avx512(
                dqs,
                &joints[..head],
                &weights[..head],
                &positions[..head],
                &normals[..head],
                &mut out_positions[..head],
                &mut out_normals[..head],
            );
        }
    }
    let full = if N.is_multiple_of(4) { head + (n - head) / 16 * 16 } else { 0 };
    let sign_bit = _mm512_castps_si512(_mm512_set1_ps(-0.0));
    let zero = _mm512_setzero_ps();
    // The N influences' dual quaternions of one group wait here until the pivot is known (it
    // is the real part of whichever has the largest weight). Held in registers, they were more
    // than the 32 there are, and the compiler's spills to the stack made the kernel's speed
    // depend on where the stack lay modulo 4 KiB: a palette load that shares its address bits
    // 11..0 with a spill store in flight waits for it ("4K aliasing"; 2.38 to 2.76 ns per vertex
    // at 100 000 vertices across stack offsets on Zen 5). Written and read explicitly
    // (volatile, so that the compiler keeps them in memory rather than in registers it then
    // spills), they leave the kernel with no spills. Where this memory lies relative to the
    // palette changed the time by 2 % at most (the scratch at the palette's own offsets
    // modulo 4 KiB against after its end), so nothing places it.
    let mut scratch: Vec<__m512> = Vec::with_capacity(8 * N);
    let sp = scratch.as_mut_ptr();
    for base in (head..full).step_by(16) {
        let js = &joints[base..base + 16];
        // The weights, four influences at a time.
        let rows = weights[base..base + 16].as_ptr().cast::<f32>();
        let mut wv = [zero; N];
        for g in 0..N / 4 {
            // SAFETY: row l's floats 4g..4g + 4, inside its N.
            let at: [*const f32; 16] = std::array::from_fn(|l| unsafe { rows.add(N * l + 4 * g) });
            // SAFETY: as above.
            let w = unsafe { rows4_soa16(&at) };
            for c in 0..4 {
                wv[4 * g + c] = w[c];
            }
        }
        // Each influence's dual quaternions, kept in the scratch until the pivot is known, and
        // the pivot: the real part of each lane's largest-weight influence (first on ties).
        let mut pivot = [zero; 4];
        let mut best = wv[0];
        // Index loops: LLVM unrolls them, while iterator adapters such as `skip` stayed calls.
        #[allow(clippy::needless_range_loop)]
        for i in 0..N {
            // SAFETY: 16 rows; every index is in `dqs` (validated).
            let part = unsafe { dual_quaternions_soa16(dqs, js, i) };
            for c in 0..8 {
                // SAFETY: register 8i + c of the scratch's capacity of 8N.
                unsafe { std::ptr::write_volatile(sp.add(8 * i + c), part[c]) };
            }
            if i == 0 {
                pivot = [part[0], part[1], part[2], part[3]];
            } else {
                let larger = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(wv[i], best);
                best = _mm512_mask_blend_ps(larger, best, wv[i]);
                for c in 0..4 {
                    pivot[c] = _mm512_mask_blend_ps(larger, pivot[c], part[c]);
                }
            }
        }
        // Blend, each weight with the sign of its real part's dot product with the pivot.
        let mut q = [zero; 8];
        #[allow(clippy::needless_range_loop)]
        for i in 0..N {
            // SAFETY: registers the loop above wrote.
            let part: [__m512; 8] =
                std::array::from_fn(|c| unsafe { std::ptr::read_volatile(sp.add(8 * i + c)) });
            let w = wv[i];
            let dot = _mm512_fmadd_ps(
                part[3],
                pivot[3],
                _mm512_fmadd_ps(
                    part[2],
                    pivot[2],
                    _mm512_fmadd_ps(part[1], pivot[1], _mm512_mul_ps(part[0], pivot[0])),
                ),
            );
            let sign = _mm512_and_si512(_mm512_castps_si512(dot), sign_bit);
            let w = _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(w), sign));
            for c in 0..8 {
                q[c] = _mm512_fmadd_ps(part[c], w, q[c]);
            }
        }
        let [rx, ry, rz, rw, dx, dy, dz, dw] = q;
        // s = 2/|r|², then R and t as in the 8-lane kernels.
        let len2 =
            _mm512_fmadd_ps(rw, rw, _mm512_fmadd_ps(rz, rz, _mm512_fmadd_ps(ry, ry, _mm512_mul_ps(rx, rx))));
        let s = _mm512_div_ps(_mm512_set1_ps(2.0), len2);
        let (sx, sy, sz) = (_mm512_mul_ps(s, rx), _mm512_mul_ps(s, ry), _mm512_mul_ps(s, rz));
        let (xx, yy, zz) = (_mm512_mul_ps(sx, rx), _mm512_mul_ps(sy, ry), _mm512_mul_ps(sz, rz));
        let (xy, xz, yz) = (_mm512_mul_ps(sx, ry), _mm512_mul_ps(sx, rz), _mm512_mul_ps(sy, rz));
        let (wx, wy, wz) = (_mm512_mul_ps(sx, rw), _mm512_mul_ps(sy, rw), _mm512_mul_ps(sz, rw));
        let one = _mm512_set1_ps(1.0);
        let m00 = _mm512_sub_ps(one, _mm512_add_ps(yy, zz));
        let m01 = _mm512_sub_ps(xy, wz);
        let m02 = _mm512_add_ps(xz, wy);
        let m10 = _mm512_add_ps(xy, wz);
        let m11 = _mm512_sub_ps(one, _mm512_add_ps(xx, zz));
        let m12 = _mm512_sub_ps(yz, wx);
        let m20 = _mm512_sub_ps(xz, wy);
        let m21 = _mm512_add_ps(yz, wx);
        let m22 = _mm512_sub_ps(one, _mm512_add_ps(xx, yy));
        let cross = |a: __m512, b: __m512, c: __m512, e: __m512| _mm512_fmsub_ps(a, b, _mm512_mul_ps(c, e));
        let tx = _mm512_mul_ps(s, _mm512_fmadd_ps(rw, dx, _mm512_fnmadd_ps(dw, rx, cross(ry, dz, rz, dy))));
        let ty = _mm512_mul_ps(s, _mm512_fmadd_ps(rw, dy, _mm512_fnmadd_ps(dw, ry, cross(rz, dx, rx, dz))));
        let tz = _mm512_mul_ps(s, _mm512_fmadd_ps(rw, dz, _mm512_fnmadd_ps(dw, rz, cross(rx, dy, ry, dx))));
        // SAFETY (all four): 16 Vec3s are 48 contiguous floats of their slices.
        let p = unsafe { load_deinterleaved16(positions[base..base + 16].as_ptr().cast::<f32>()) };
        let n = unsafe { load_deinterleaved16(normals[base..base + 16].as_ptr().cast::<f32>()) };
        let (px, py, pz) =
            (row16(m00, m01, m02, p, tx), row16(m10, m11, m12, p, ty), row16(m20, m21, m22, p, tz));
        let (nx, ny, nz) =
            (row16(m00, m01, m02, n, zero), row16(m10, m11, m12, n, zero), row16(m20, m21, m22, n, zero));
        unsafe {
            store_interleaved16(
                out_positions[base..base + 16].as_mut_ptr().cast::<f32>(),
                px,
                py,
                pz,
                stream,
            );
            store_interleaved16(out_normals[base..base + 16].as_mut_ptr().cast::<f32>(), nx, ny, nz, stream);
        }
    }
    // SAFETY: the caller's contract (the same CPU features).
    unsafe {
        dual_quaternion_chunk_soa_avx512(
            dqs,
            &joints[full..],
            &weights[full..],
            &positions[full..],
            &normals[full..],
            &mut out_positions[full..],
            &mut out_normals[full..],
        );
    }
    if stream {
        // Streaming stores are weakly ordered: make them visible before the chunk is reported
        // done (to another thread, through the chunk counter's release store).
        _mm_sfence();
    }
}

/// `_MM_SHUFFLE(z, y, x, w)` (not yet stable as a const fn).
const fn shuffle_imm(z: i32, y: i32, x: i32, w: i32) -> i32 {
    (z << 6) + (y << 4) + (x << 2) + w
}

/// Packs four results (x, y, z, _) into the three registers x₀y₀z₀x₁, y₁z₁x₂y₂, z₂x₃y₃z₃: four
/// `Vec3` as they lie in memory, written with three 16-byte stores.
#[target_feature(enable = "avx2,fma")]
fn pack4(r0: __m128, r1: __m128, r2: __m128, r3: __m128) -> [__m128; 3] {
    let a = _mm_insert_ps::<0x30>(r0, r1);
    let b = _mm_shuffle_ps::<{ shuffle_imm(1, 0, 2, 1) }>(r1, r2);
    let t = _mm_shuffle_ps::<{ shuffle_imm(0, 0, 2, 2) }>(r2, r3);
    let c = _mm_shuffle_ps::<{ shuffle_imm(2, 1, 2, 0) }>(t, r3);
    [a, b, c]
}

/// Rigid skinning of one chunk: v' = M(j)·v, n' = N(j)·n, with N(j) = M(j)'s linear part when
/// `normal_palette` is `None`. Each coordinate is broadcast straight from memory into an FMA
/// with a palette column; four vertices at a time are packed into three registers per output
/// and stored whole, instead of the portable loop's 12-byte stores.
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`Features::run_avx2_fma`]); every joint index must be in `palette`
/// and in `normal_palette` (validated); all slices have the same length.
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn rigid_chunk(
    palette: &[Affine3A],
    normal_palette: Option<&[Mat3A]>,
    joints: &[u16],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    let n = positions.len();
    debug_assert!([joints.len(), normals.len(), out_positions.len(), out_normals.len()]
        .iter()
        .all(|&l| l == n));
    let (pp, np) = (positions.as_ptr() as *const f32, normals.as_ptr() as *const f32);
    let (opp, onp) = (out_positions.as_mut_ptr() as *mut f32, out_normals.as_mut_ptr() as *mut f32);
    // SAFETY (all closures): v < n, the joint is in both palettes (the caller's contract).
    let one = |v: usize| -> (__m128, __m128) {
        let j = *joints.get_unchecked(v) as usize;
        let m = palette.get_unchecked(j);
        let (c0, c1, c2): (__m128, __m128, __m128) =
            (m.matrix3.x_axis.into(), m.matrix3.y_axis.into(), m.matrix3.z_axis.into());
        let c3: __m128 = m.translation.into();
        let p = pp.add(3 * v);
        let pos = _mm_fmadd_ps(
            c0,
            _mm_broadcast_ss(&*p),
            _mm_fmadd_ps(
                c1,
                _mm_broadcast_ss(&*p.add(1)),
                _mm_fmadd_ps(c2, _mm_broadcast_ss(&*p.add(2)), c3),
            ),
        );
        let (d0, d1, d2) = match normal_palette {
            Some(normal_palette) => {
                let nm = normal_palette.get_unchecked(j);
                (nm.x_axis.into(), nm.y_axis.into(), nm.z_axis.into())
            }
            None => (c0, c1, c2),
        };
        let q = np.add(3 * v);
        let nor = _mm_fmadd_ps(
            d0,
            _mm_broadcast_ss(&*q),
            _mm_fmadd_ps(d1, _mm_broadcast_ss(&*q.add(1)), _mm_mul_ps(d2, _mm_broadcast_ss(&*q.add(2)))),
        );
        (pos, nor)
    };
    let mut v = 0;
    while v + 4 <= n {
        let (p0, n0) = one(v);
        let (p1, n1) = one(v + 1);
        let (p2, n2) = one(v + 2);
        let (p3, n3) = one(v + 3);
        let (ps, ns) = (pack4(p0, p1, p2, p3), pack4(n0, n1, n2, n3));
        let (po, no) = (opp.add(3 * v), onp.add(3 * v));
        for k in 0..3 {
            _mm_storeu_ps(po.add(4 * k), ps[k]);
            _mm_storeu_ps(no.add(4 * k), ns[k]);
        }
        v += 4;
    }
    while v < n {
        let (pos, nor) = one(v);
        *out_positions.get_unchecked_mut(v) = Vec3A::from(pos).into();
        *out_normals.get_unchecked_mut(v) = Vec3A::from(nor).into();
        v += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The last-level cache size read from CPUID is the one Linux reports in sysfs (which the
    /// kernel reads from the same CPUID leaves): the largest-level data or unified cache.
    #[test]
    fn the_last_level_cache_size_is_the_one_linux_reports() {
        let dir = std::path::Path::new("/sys/devices/system/cpu/cpu0/cache");
        let read = |path: std::path::PathBuf| std::fs::read_to_string(path).ok().map(|s| s.trim().to_owned());
        let mut largest: Option<(u32, usize)> = None;
        for entry in std::fs::read_dir(dir).expect("sysfs lists the CPU's caches (Linux)") {
            let path = entry.expect("a cache entry").path();
            let (Some(level), Some(kind), Some(size)) =
                (read(path.join("level")), read(path.join("type")), read(path.join("size")))
            else {
                continue;
            };
            if kind == "Instruction" {
                continue;
            }
            let level: u32 = level.parse().expect("a cache level");
            let bytes: usize = match size.strip_suffix('K') {
                Some(k) => k.parse::<usize>().expect("a size in KiB") << 10,
                None => size.parse().expect("a size in bytes"),
            };
            if largest.is_none_or(|(l, _)| level > l) {
                largest = Some((level, bytes));
            }
        }
        let (level, bytes) = largest.expect("sysfs reports a data or unified cache");
        assert_eq!(last_level_cache_bytes(), Some(bytes), "level {level} cache");
    }

    /// What the kernels are told this CPU has is what Linux reports in /proc/cpuinfo (read
    /// from the same CPUID bits, independently of std's detection).
    #[test]
    fn detected_features_are_the_ones_linux_reports() {
        let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").expect("/proc/cpuinfo (Linux)");
        let flags: Vec<&str> = cpuinfo
            .lines()
            .find_map(|line| line.strip_prefix("flags"))
            .and_then(|rest| rest.split_once(':'))
            .expect("a flags line in /proc/cpuinfo")
            .1
            .split_whitespace()
            .collect();
        let has = |flag: &str| flags.contains(&flag);
        let expected = Features {
            avx2: has("avx2"),
            fma: has("fma"),
            avx512f: has("avx512f"),
            avx512vl: has("avx512vl"),
        };
        assert_eq!(Features::detect(), expected);
    }

    /// Each build needs every feature its instructions use: a CPU that lacks any one of them
    /// never runs it (it would fault on the first such instruction).
    #[test]
    fn a_build_runs_only_with_every_feature_it_uses() {
        let all = Features { avx2: true, fma: true, avx512f: true, avx512vl: true };
        assert!(all.run_avx2_fma() && all.run_avx512vl());
        assert!(!Features::default().run_avx2_fma() && !Features::default().run_avx512vl());
        for (without, features) in
            [("avx2", Features { avx2: false, ..all }), ("fma", Features { fma: false, ..all })]
        {
            assert!(!features.run_avx2_fma(), "AVX2+FMA build without {without}");
            assert!(!features.run_avx512vl(), "AVX-512VL build without {without}");
        }
        for (without, features) in [
            ("avx512f", Features { avx512f: false, ..all }),
            ("avx512vl", Features { avx512vl: false, ..all }),
        ] {
            assert!(features.run_avx2_fma(), "AVX2+FMA build needs no {without}");
            assert!(!features.run_avx512vl(), "AVX-512VL build without {without}");
        }
    }

    /// Outputs stream past the cache only when the job's bytes exceed it, never when its size is
    /// unknown, and a vertex count whose bytes overflow is larger than any cache.
    #[test]
    fn outputs_stream_when_the_job_exceeds_the_cache() {
        let cache = Some(72 * 1000);
        assert!(!larger_than_cache(1000, 4, cache), "exactly the cache's size");
        assert!(larger_than_cache(1001, 4, cache));
        assert!(!larger_than_cache(1000, 8, Some(96 * 1000)) && larger_than_cache(1001, 8, Some(96 * 1000)));
        assert!(!larger_than_cache(1 << 40, 4, None));
        assert!(larger_than_cache(usize::MAX / 8, 4, Some(usize::MAX - 1)));
    }

    /// A made-up CPU for [`last_level_cache_from`]: its vendor string, highest standard and
    /// extended leaves, and the caches its deterministic-cache-parameters leaf lists.
    struct FakeCpu {
        vendor: &'static [u8; 12],
        max_leaf: u32,
        max_extended_leaf: u32,
        topology_extensions: bool,
        /// (type: 1 data, 2 instruction, 3 unified; level; ways; partitions; line bytes; sets)
        caches: Vec<(u32, u32, u32, u32, u32, u32)>,
    }

    impl FakeCpu {
        fn cpuid(&self, leaf: u32, sub_leaf: u32) -> [u32; 4] {
            let word = |i: usize| u32::from_le_bytes(self.vendor[4 * i..4 * i + 4].try_into().unwrap());
            let cache_leaf = if self.vendor == b"GenuineIntel" { 4 } else { 0x8000_001D };
            match leaf {
                // The vendor string is EBX, EDX, ECX.
                0 => [self.max_leaf, word(0), word(2), word(1)],
                0x8000_0000 => [self.max_extended_leaf, 0, 0, 0],
                0x8000_0001 => [0, 0, u32::from(self.topology_extensions) << 22, 0],
                _ if leaf == cache_leaf => self.caches.get(sub_leaf as usize).map_or([0; 4], |c| {
                    let (kind, level, ways, partitions, line, sets) = *c;
                    // The layout of Intel's SDM (CPUID leaf 04H), which AMD's 8000_001DH shares.
                    [kind | level << 5, (ways - 1) << 22 | (partitions - 1) << 12 | (line - 1), sets - 1, 0]
                }),
                _ => [0; 4],
            }
        }

        fn last_level_cache(&self) -> Option<usize> {
            last_level_cache_from(|leaf, sub_leaf| self.cpuid(leaf, sub_leaf))
        }
    }

    const MIB: usize = 1 << 20;

    /// An Intel client CPU: 48 KiB L1d (12 ways × 64 sets × 64 B), 32 KiB L1i, 1.25 MiB L2
    /// (10 × 2048 × 64), 24 MiB L3 (12 × 32768 × 64).
    fn intel() -> FakeCpu {
        FakeCpu {
            vendor: b"GenuineIntel",
            max_leaf: 0x20,
            max_extended_leaf: 0x8000_0008,
            topology_extensions: false,
            caches: vec![
                (1, 1, 12, 1, 64, 64),
                (2, 1, 8, 1, 64, 64),
                (3, 2, 10, 1, 64, 2048),
                (3, 3, 12, 1, 64, 32768),
            ],
        }
    }

    /// An AMD Zen CPU: 32 KiB L1d and L1i, 1 MiB L2, 32 MiB L3 (16 × 32768 × 64) per CCX.
    fn amd(vendor: &'static [u8; 12]) -> FakeCpu {
        FakeCpu {
            vendor,
            max_leaf: 0x10,
            max_extended_leaf: 0x8000_0021,
            topology_extensions: true,
            caches: vec![
                (1, 1, 8, 1, 64, 64),
                (2, 1, 8, 1, 64, 64),
                (3, 2, 8, 1, 64, 2048),
                (3, 3, 16, 1, 64, 32768),
            ],
        }
    }

    #[test]
    fn the_last_level_cache_is_read_from_each_vendors_leaf() {
        assert_eq!(intel().last_level_cache(), Some(24 * MIB));
        assert_eq!(amd(b"AuthenticAMD").last_level_cache(), Some(32 * MIB));
        assert_eq!(amd(b"HygonGenuine").last_level_cache(), Some(32 * MIB));
        // AMD's caches are not read from Intel's leaf, nor Intel's from AMD's.
        assert_eq!(FakeCpu { vendor: b"AuthenticAMD", ..intel() }.last_level_cache(), None);
        assert_eq!(
            FakeCpu { vendor: b"GenuineIntel", ..amd(b"AuthenticAMD") }.last_level_cache(),
            Some(32 * MIB)
        );
    }

    #[test]
    fn a_cpu_without_the_cache_leaf_has_no_known_cache_size() {
        // Leaf 4 is beyond an old Intel CPU's highest leaf (whatever it would return).
        assert_eq!(FakeCpu { max_leaf: 3, ..intel() }.last_level_cache(), None);
        assert_eq!(FakeCpu { max_leaf: 4, ..intel() }.last_level_cache(), Some(24 * MIB));
        // AMD: leaf 0x8000_001D needs both the extended leaf and the topology extensions bit.
        let amd = || amd(b"AuthenticAMD");
        assert_eq!(FakeCpu { max_extended_leaf: 0x8000_001C, ..amd() }.last_level_cache(), None);
        assert_eq!(FakeCpu { max_extended_leaf: 0x8000_001D, ..amd() }.last_level_cache(), Some(32 * MIB));
        assert_eq!(FakeCpu { topology_extensions: false, ..amd() }.last_level_cache(), None);
        assert_eq!(FakeCpu { caches: Vec::new(), ..intel() }.last_level_cache(), None);
    }

    #[test]
    fn the_last_level_is_the_highest_data_or_unified_cache_with_all_its_partitions() {
        // A level-2 cache larger than the level-3 one: the level decides, not the size.
        let caches = vec![(1, 1, 8, 1, 64, 64), (3, 2, 16, 1, 64, 4096), (3, 3, 16, 1, 64, 2048)];
        assert_eq!(FakeCpu { caches, ..intel() }.last_level_cache(), Some(2 * MIB));
        // A cache in two partitions holds twice what one does (16 ways × 2 × 64 B × 8192 sets).
        let caches = vec![(1, 1, 8, 1, 64, 64), (3, 3, 16, 2, 64, 8192)];
        assert_eq!(FakeCpu { caches, ..intel() }.last_level_cache(), Some(16 * MIB));
        // An instruction cache is no place for outputs, even at the highest level.
        let caches = vec![(1, 1, 8, 1, 64, 64), (3, 2, 8, 1, 64, 2048), (2, 3, 16, 1, 64, 32768)];
        assert_eq!(FakeCpu { caches, ..intel() }.last_level_cache(), Some(MIB));
        // The list ends at the first null entry (type 0); what follows it is not a cache.
        let caches = vec![(1, 1, 8, 1, 64, 64), (0, 0, 1, 1, 1, 1), (3, 3, 16, 1, 64, 32768)];
        assert_eq!(FakeCpu { caches, ..intel() }.last_level_cache(), Some(32 * 1024));
        // Line size and sets count as well as ways.
        let caches = vec![(3, 3, 1, 1, 128, 1)];
        assert_eq!(FakeCpu { caches, ..intel() }.last_level_cache(), Some(128));
    }

    #[test]
    fn a_four_influence_vertex_moves_72_bytes() {
        assert_eq!(bytes_per_vertex(4), 72);
        assert_eq!(bytes_per_vertex(8), 96);
        assert_eq!(bytes_per_vertex(1), 54);
    }

    /// The 8-lane sin and cos agree with the scalar polynomials and libm over the whole
    /// quarter turn, where the x¹¹ and x¹² terms matter (3.6e-6 at π/2).
    #[test]
    fn eight_lane_sin_cos_matches_the_scalar_polynomials() {
        assert!(
            Features::detect().run_avx2_fma(),
            "this test checks the AVX2+FMA build: the CPU has no AVX2 or FMA"
        );
        for i in 0..=125 {
            let xs: [f32; 8] = std::array::from_fn(|k| {
                (std::f32::consts::FRAC_PI_2 * (8 * i + k) as f32 / 1000.0).min(std::f32::consts::FRAC_PI_2)
            });
            // SAFETY: the CPU has AVX2 and FMA (checked above).
            let (s, c) = unsafe {
                let (s, c) = sin_cos_quarter_turn_x8(_mm256_loadu_ps(xs.as_ptr()));
                let (mut s_out, mut c_out) = ([0.0f32; 8], [0.0f32; 8]);
                _mm256_storeu_ps(s_out.as_mut_ptr(), s);
                _mm256_storeu_ps(c_out.as_mut_ptr(), c);
                (s_out, c_out)
            };
            for k in 0..8 {
                let x = xs[k];
                let (want_s, want_c) = sin_cos_quarter_turn(x);
                assert!((s[k] - want_s).abs() < 2e-7 && (s[k] - x.sin()).abs() < 3e-7, "sin({x}): {}", s[k]);
                assert!((c[k] - want_c).abs() < 2e-7 && (c[k] - x.cos()).abs() < 3e-7, "cos({x}): {}", c[k]);
            }
        }
    }
}
