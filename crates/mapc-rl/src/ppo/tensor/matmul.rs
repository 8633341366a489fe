//! The update's matrix products, for its shapes: a few hundred rows at most, 1 to a few hundred columns. Each
//! output element is one fused multiply-add per term, the terms taken in order, so the AVX-512, the AVX2 and the
//! plain copy give the same bits on every machine (a test checks it).
//!
//! Why not gemm (through burn's flex backend): at these sizes its packing, dispatch and tensor allocations cost
//! about as much as its arithmetic, and its stable build has no AVX-512 kernels (docs/perf.md, "The update's
//! matrix products").

/// The operands of `c += a b`: `a` is `rows × terms`, element (i, t) at `a[i * a_row + t * a_term]` (a transposed
/// matrix is other strides), `b` is `terms × cols` row-major.
#[derive(Clone, Copy)]
pub(super) struct Product<'a> {
    pub rows: usize,
    pub cols: usize,
    pub terms: usize,
    pub a: &'a [f32],
    pub a_row: usize,
    pub a_term: usize,
    pub b: &'a [f32],
}

impl Product<'_> {
    #[inline(always)]
    fn a_at(&self, i: usize, t: usize) -> usize {
        i * self.a_row + t * self.a_term
    }
}

/// `c[i][j] = fma(a(i, t), b[t][j], c[i][j])` for t = 0, 1, ... `terms - 1` in order: `c` is `rows × cols`
/// row-major and holds the starting values (a bias, or zeros).
pub(super) fn accumulate(p: Product, c: &mut [f32]) {
    let Product {
        rows, cols, terms, ..
    } = p;
    if rows == 0 || cols == 0 || terms == 0 {
        return;
    }
    assert!(
        p.a_at(rows - 1, terms - 1) < p.a.len(),
        "a is too short for {rows} x {terms}"
    );
    assert!(
        terms * cols <= p.b.len(),
        "b is too short for {terms} x {cols}"
    );
    assert!(rows * cols <= c.len(), "c is too short for {rows} x {cols}");
    match kernel() {
        // SAFETY: the CPU has AVX-512F ([`kernel`]); the operands' sizes are checked above.
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx512 => unsafe { x86::accumulate_avx512(p, c) },
        // SAFETY: the CPU has AVX2 and FMA ([`kernel`]); the operands' sizes are checked above.
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx2 => unsafe { x86::accumulate_avx2(p, c) },
        _ => accumulate_plain(p, c),
    }
}

/// The copies of [`accumulate`].
#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
enum Kernel {
    Avx512,
    Avx2,
    Plain,
}

/// The widest copy this CPU runs.
fn kernel() -> Kernel {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") {
            return Kernel::Avx512;
        }
        if has!("avx2") && has!("fma") {
            return Kernel::Avx2;
        }
    }
    Kernel::Plain
}

/// [`accumulate`] one element at a time (`mul_add` is a correctly rounded fused multiply-add everywhere).
pub(super) fn accumulate_plain(p: Product, c: &mut [f32]) {
    for i in 0..p.rows {
        let out = &mut c[i * p.cols..][..p.cols];
        for t in 0..p.terms {
            let x = p.a[p.a_at(i, t)];
            for (o, &y) in out.iter_mut().zip(&p.b[t * p.cols..][..p.cols]) {
                *o = x.mul_add(y, *o);
            }
        }
    }
}

/// Which kernel [`accumulate`] takes on this CPU, for `mapc bench`.
pub fn kernel_name() -> &'static str {
    match kernel() {
        Kernel::Avx512 => "AVX-512",
        Kernel::Avx2 => "AVX2+FMA",
        Kernel::Plain => "scalar fused multiply-add",
    }
}

/// Register blocks: four rows of `c` by up to four vectors of columns stay in registers while the terms stream
/// past; each term loads the block's columns of `b` once and broadcasts one element of `a` per row.
#[cfg(target_arch = "x86_64")]
pub(super) mod x86 {
    use super::Product;
    use std::arch::x86_64::*;

    const ROWS: usize = 4;

    macro_rules! driver {
        ($name:ident, $block:ident, $feature:literal, $lanes:expr) => {
            #[target_feature(enable = $feature)]
            pub(in super::super) unsafe fn $name(p: Product, c: &mut [f32]) {
                let (rows, cols) = (p.rows, p.cols);
                let mut i = 0;
                while i < rows {
                    let r = (rows - i).min(ROWS);
                    let mut j = 0;
                    while j < cols {
                        let width = (cols - j).min(4 * $lanes);
                        let vectors = width.div_ceil($lanes);
                        // SAFETY: rows i..i + r and columns j..j + width lie within the checked sizes.
                        unsafe {
                            match (r, vectors) {
                                (4, 4) => $block::<4, 4>(i, j, width, p, c),
                                (4, 3) => $block::<4, 3>(i, j, width, p, c),
                                (4, 2) => $block::<4, 2>(i, j, width, p, c),
                                (4, _) => $block::<4, 1>(i, j, width, p, c),
                                (3, 4) => $block::<3, 4>(i, j, width, p, c),
                                (3, 3) => $block::<3, 3>(i, j, width, p, c),
                                (3, 2) => $block::<3, 2>(i, j, width, p, c),
                                (3, _) => $block::<3, 1>(i, j, width, p, c),
                                (2, 4) => $block::<2, 4>(i, j, width, p, c),
                                (2, 3) => $block::<2, 3>(i, j, width, p, c),
                                (2, 2) => $block::<2, 2>(i, j, width, p, c),
                                (2, _) => $block::<2, 1>(i, j, width, p, c),
                                (_, 4) => $block::<1, 4>(i, j, width, p, c),
                                (_, 3) => $block::<1, 3>(i, j, width, p, c),
                                (_, 2) => $block::<1, 2>(i, j, width, p, c),
                                (_, _) => $block::<1, 1>(i, j, width, p, c),
                            }
                        }
                        j += width;
                    }
                    i += r;
                }
            }
        };
    }

    driver!(accumulate_avx512, block_avx512, "avx512f", 16);
    driver!(accumulate_avx2, block_avx2, "avx2,fma", 8);

    /// `fn NAME<R, V>`: rows `i0..i0 + R` by columns `j0..j0 + width` of `c`, with `width` in
    /// (LANES (V - 1), LANES V], for one instruction set: its vector type, lanes, intrinsics, and the mask of the
    /// last vector, whose lanes past `width` are never read or written (every other vector is full).
    macro_rules! block {
        (
            $name:ident, $feature:literal, $vector:ty, $lanes:literal,
            zero: $zero:ident, splat: $splat:ident, fma: $fma:ident, load: $load:ident, store: $store:ident,
            tail($tail_lanes:ident) = $tail:expr,
            load_tail($lp:ident) = $load_tail:expr,
            store_tail($sp:ident, $sx:ident) = $store_tail:expr $(,)?
        ) => {
            #[target_feature(enable = $feature)]
            unsafe fn $name<const R: usize, const V: usize>(
                i0: usize,
                j0: usize,
                width: usize,
                p: Product,
                c: &mut [f32],
            ) {
                let cols = p.cols;
                let $tail_lanes = width - $lanes * (V - 1);
                let tail = $tail;
                let c_at = |r: usize, v: usize| (i0 + r) * cols + j0 + $lanes * v;
                let mut acc: [[$vector; V]; R] = [[$zero(); V]; R];
                // SAFETY (every pointer read and write below): each vector starts inside its row of `c` or `b`,
                // and the last one's lanes past the row's `width` columns are masked off.
                unsafe {
                    let load = |$lp: *const f32, v: usize| {
                        if v + 1 == V {
                            $load_tail(tail)
                        } else {
                            $load($lp)
                        }
                    };
                    for (r, row) in acc.iter_mut().enumerate() {
                        for (v, x) in row.iter_mut().enumerate() {
                            *x = load(c.as_ptr().add(c_at(r, v)), v);
                        }
                    }
                    let a_ptr = p.a.as_ptr();
                    for t in 0..p.terms {
                        let b_ptr = p.b.as_ptr().add(t * cols + j0);
                        let mut bv: [$vector; V] = [$zero(); V];
                        for (v, x) in bv.iter_mut().enumerate() {
                            *x = load(b_ptr.add($lanes * v), v);
                        }
                        for (r, row) in acc.iter_mut().enumerate() {
                            let x = $splat(*a_ptr.add(p.a_at(i0 + r, t)));
                            for (y, &w) in row.iter_mut().zip(&bv) {
                                *y = $fma(x, w, *y);
                            }
                        }
                    }
                    for (r, row) in acc.iter().enumerate() {
                        for (v, &$sx) in row.iter().enumerate() {
                            let $sp = c.as_mut_ptr().add(c_at(r, v));
                            if v + 1 == V {
                                $store_tail(tail);
                            } else {
                                $store($sp, $sx);
                            }
                        }
                    }
                }
            }
        };
    }

    block!(
        block_avx512, "avx512f", __m512, 16,
        zero: _mm512_setzero_ps, splat: _mm512_set1_ps, fma: _mm512_fmadd_ps,
        load: _mm512_loadu_ps, store: _mm512_storeu_ps,
        tail(lanes) = ((1u32 << lanes) - 1) as __mmask16,
        load_tail(p) = |mask| _mm512_maskz_loadu_ps(mask, p),
        store_tail(p, x) = |mask| _mm512_mask_storeu_ps(p, mask, x),
    );
    block!(
        block_avx2, "avx2,fma", __m256, 8,
        zero: _mm256_setzero_ps, splat: _mm256_set1_ps, fma: _mm256_fmadd_ps,
        load: _mm256_loadu_ps, store: _mm256_storeu_ps,
        tail(lanes) = _mm256_cmpgt_epi32(
            _mm256_set1_epi32(lanes as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        ),
        load_tail(p) = |mask| _mm256_maskload_ps(p, mask),
        store_tail(p, x) = |mask| _mm256_maskstore_ps(p, mask, x),
    );
}
