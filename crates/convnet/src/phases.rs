//! One input plane zero-padded by `pad` on every side and split by phase:
//! padded pixel `(Y, X)` goes to phase `(Y % stride, X % stride)`, row
//! `Y / stride`, column `X / stride`. Output `(oy, ox)` of kernel offset
//! `(ky, kx)` reads padded pixel `(oy stride + ky, ox stride + kx)`, which
//! is phase `(ky % stride, kx % stride)`, row `oy + ky / stride`, column
//! `ox + kx / stride`: a row of outputs reads `wout` contiguous values,
//! always inside the buffer, so im2col copies (and col2im adds) whole rows
//! without a bounds test or a strided access.
use crate::layout::LayerShape;

/// The split layout of one layer's input plane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Phases {
    stride: usize,
    pad: usize,
    hin: usize,
    win: usize,
    /// Rows of one phase.
    rows: usize,
    /// Columns of one phase (the distance between its rows).
    pub cols: usize,
}

impl Phases {
    #[inline(always)]
    pub fn new(s: &LayerShape) -> Self {
        Phases {
            stride: s.stride,
            pad: s.pad,
            hin: s.hin,
            win: s.win,
            rows: (s.hin + 2 * s.pad).div_ceil(s.stride),
            cols: (s.win + 2 * s.pad).div_ceil(s.stride),
        }
    }

    /// Values of the buffer: `stride^2` phases of `rows x cols`.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.stride * self.stride * self.rows * self.cols
    }

    /// Where kernel offset `(ky, kx)`'s first output row reads (row `oy`:
    /// `oy * cols` further on).
    #[inline(always)]
    pub fn tap(&self, ky: usize, kx: usize) -> usize {
        let st = self.stride;
        (((ky % st) * st + kx % st) * self.rows + ky / st) * self.cols + kx / st
    }

    /// `buf = split(plane)` at the input's places (`plane` is `hin x
    /// win`); the padding is left as it is.
    #[inline(always)]
    pub fn split(&self, plane: &[f32], buf: &mut [f32]) {
        if self.stride == 2 {
            self.split_pairs(plane, buf);
            return;
        }
        for run in self.runs() {
            let src = &plane[run.row * self.win..][..self.win];
            gather(
                &mut buf[run.at..][..run.len],
                &src[run.first..],
                self.stride,
            );
        }
    }

    /// `plane = merge(buf)`, the inverse of [`Self::split`] (the padding
    /// is dropped).
    #[inline(always)]
    pub fn merge(&self, buf: &[f32], plane: &mut [f32]) {
        if self.stride == 2 {
            self.merge_pairs(buf, plane);
            return;
        }
        for run in self.runs() {
            let dst = &mut plane[run.row * self.win..][..self.win];
            scatter(
                &mut dst[run.first..],
                &buf[run.at..][..run.len],
                self.stride,
            );
        }
    }

    /// [`Self::split`] at stride 2, a row at a time (see
    /// [`Self::merge_pairs`]): one pass over the row fills both runs.
    #[inline(always)]
    fn split_pairs(&self, plane: &[f32], buf: &mut [f32]) {
        let pad = self.pad;
        let (half_up, half_down) = (self.win.div_ceil(2), self.win / 2);
        for (iy, row) in plane.chunks_exact(self.win).take(self.hin).enumerate() {
            let (ry, y) = ((iy + pad) % 2, (iy + pad) / 2);
            let even_at = self.start(ry, pad % 2, y) + pad / 2;
            let odd_at = self.start(ry, (pad + 1) % 2, y) + pad.div_ceil(2);
            let (even, odd) = two_runs(buf, (even_at, half_up), (odd_at, half_down));
            for ((s, a), b) in row.chunks_exact(2).zip(even.iter_mut()).zip(odd) {
                *a = s[0];
                *b = s[1];
            }
            if self.win % 2 == 1 {
                even[half_down] = row[self.win - 1];
            }
        }
    }

    /// Where row `y` of phase `(ry, rx)` starts in the buffer.
    #[inline(always)]
    fn start(&self, ry: usize, rx: usize, y: usize) -> usize {
        ((ry * self.stride + rx) * self.rows + y) * self.cols
    }

    /// [`Self::merge`] at stride 2, a row at a time: input column `2i`
    /// is phase column `pad % 2`'s value `i + pad / 2`, column `2i + 1`
    /// phase column `(pad + 1) % 2`'s value `i + pad.div_ceil(2)`, so a row
    /// interleaves two contiguous runs (vector shuffles, not a strided
    /// store a value at a time).
    #[inline(always)]
    fn merge_pairs(&self, buf: &[f32], plane: &mut [f32]) {
        let pad = self.pad;
        for (iy, row) in plane.chunks_exact_mut(self.win).take(self.hin).enumerate() {
            let (ry, y) = ((iy + pad) % 2, (iy + pad) / 2);
            let even = &buf[self.start(ry, pad % 2, y) + pad / 2..][..self.win.div_ceil(2)];
            let odd = &buf[self.start(ry, (pad + 1) % 2, y) + pad.div_ceil(2)..][..self.win / 2];
            for ((d, a), b) in row.chunks_exact_mut(2).zip(even).zip(odd) {
                d[0] = *a;
                d[1] = *b;
            }
            if self.win % 2 == 1 {
                row[self.win - 1] = even[self.win / 2];
            }
        }
    }

    /// Every phase row's run of input values (any stride; stride 2 has
    /// its own loops by pairs).
    fn runs(&self) -> impl Iterator<Item = Run> + '_ {
        let columns = (0..self.stride).filter_map(move |rx| Some((rx, self.columns(rx)?)));
        columns.flat_map(move |(rx, (lo, hi, first))| {
            let rows = (0..self.stride).flat_map(move |ry| (0..self.rows).map(move |y| (ry, y)));
            rows.filter_map(move |(ry, y)| {
                let (row, at) = self.row(rx, ry, y)?;
                Some(Run {
                    row,
                    at: at + lo,
                    len: hi - lo,
                    first,
                })
            })
        })
    }

    /// The columns `lo..hi` of phase column `rx` that hold input, the
    /// first of them input column `first` (then `first + stride`, ...);
    /// `None` if none does.
    #[inline(always)]
    fn columns(&self, rx: usize) -> Option<(usize, usize, usize)> {
        let (st, pad) = (self.stride, self.pad);
        let hi = (pad + self.win)
            .saturating_sub(rx)
            .div_ceil(st)
            .min(self.cols);
        let lo = pad.saturating_sub(rx).div_ceil(st).min(hi);
        (lo < hi).then(|| (lo, hi, lo * st + rx - pad))
    }

    /// Row `y` of phase `(ry, rx)`: the input row it holds and where it
    /// starts in the buffer; `None` for a row of padding.
    #[inline(always)]
    fn row(&self, rx: usize, ry: usize, y: usize) -> Option<(usize, usize)> {
        let (st, pad) = (self.stride, self.pad);
        let py = y * st + ry;
        let at = self.start(ry, rx, y);
        (py >= pad && py - pad < self.hin).then_some((py - pad, at))
    }
}

/// One phase row's input values: `len` of them from `at` in the buffer,
/// input row `row`'s columns `first, first + stride, ...`.
#[derive(Debug, Clone, Copy)]
struct Run {
    row: usize,
    at: usize,
    len: usize,
    first: usize,
}

/// The runs `buf[a.0..][..a.1]` and `buf[b.0..][..b.1]`, which do not
/// overlap (they lie in different phases), both to write.
#[inline(always)]
fn two_runs(buf: &mut [f32], a: (usize, usize), b: (usize, usize)) -> (&mut [f32], &mut [f32]) {
    if a.0 < b.0 {
        let (low, high) = buf.split_at_mut(b.0);
        (&mut low[a.0..][..a.1], &mut high[..b.1])
    } else {
        let (low, high) = buf.split_at_mut(a.0);
        (&mut high[..a.1], &mut low[b.0..][..b.1])
    }
}

/// `dst[r][..w] = src[r * pitch..][..w]`, `dst` holding whole rows of `w`
/// (fixed-length copies for the usual widths, so each row is a few vector
/// moves, not a call).
#[inline(always)]
pub(crate) fn copy_rows(dst: &mut [f32], src: &[f32], w: usize, pitch: usize) {
    match w {
        8 => copy_fixed::<8>(dst, src, pitch),
        16 => copy_fixed::<16>(dst, src, pitch),
        32 => copy_fixed::<32>(dst, src, pitch),
        _ => {
            for (r, d) in dst.chunks_exact_mut(w).enumerate() {
                d.copy_from_slice(&src[r * pitch..][..w]);
            }
        }
    }
}

#[inline(always)]
fn copy_fixed<const W: usize>(dst: &mut [f32], src: &[f32], pitch: usize) {
    for (r, d) in dst.chunks_exact_mut(W).enumerate() {
        d.copy_from_slice(&src[r * pitch..][..W]);
    }
}

/// `dst[r * pitch..][..w] += src[r][..w]`, `src` holding whole rows of `w`.
#[inline(always)]
pub(crate) fn add_rows(dst: &mut [f32], src: &[f32], w: usize, pitch: usize) {
    match w {
        8 => add_fixed::<8>(dst, src, pitch),
        16 => add_fixed::<16>(dst, src, pitch),
        32 => add_fixed::<32>(dst, src, pitch),
        _ => {
            for (r, s) in src.chunks_exact(w).enumerate() {
                let d = &mut dst[r * pitch..][..w];
                d.iter_mut().zip(s).for_each(|(d, s)| *d += *s);
            }
        }
    }
}

#[inline(always)]
fn add_fixed<const W: usize>(dst: &mut [f32], src: &[f32], pitch: usize) {
    for (r, s) in src.chunks_exact(W).enumerate() {
        let d = &mut dst[r * pitch..][..W];
        for i in 0..W {
            d[i] += s[i];
        }
    }
}

/// `dst[i * stride] = src[i]`.
#[inline(always)]
fn scatter(dst: &mut [f32], src: &[f32], stride: usize) {
    if stride == 1 {
        dst[..src.len()].copy_from_slice(src);
        return;
    }
    for (d, v) in dst.iter_mut().step_by(stride).zip(src) {
        *d = *v;
    }
}

/// `dst[i] = src[i * stride]`.
#[inline(always)]
fn gather(dst: &mut [f32], src: &[f32], stride: usize) {
    if stride == 2 {
        // Whole pairs, so the compiler loads vectors and keeps the even
        // lanes; the last pixel may have no partner.
        let full = dst.len().min(src.len() / 2);
        for (d, pair) in dst[..full].iter_mut().zip(src.chunks_exact(2)) {
            *d = pair[0];
        }
        if full < dst.len() {
            dst[full] = src[2 * full];
        }
        return;
    }
    if stride == 1 {
        dst.copy_from_slice(&src[..dst.len()]);
        return;
    }
    for (d, c) in dst.iter_mut().zip(src.chunks(stride)) {
        *d = c[0];
    }
}
