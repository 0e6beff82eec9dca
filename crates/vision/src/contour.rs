//! Border following on a binary image (Suzuki & Abe 1985), reproducing what
//! OpenCV's `findContours(RETR_LIST, CHAIN_APPROX_NONE)` returns: the outer
//! border of every 8-connected white component and the border of every
//! 4-connected hole, each as the full closed sequence of boundary pixels.
//! The blob detector (report ch. 4.1) measures its blobs on these polygons,
//! so their exact shape fixes the areas, perimeters and centres it reports.

/// Pixel offsets of the eight chain directions, counter-clockwise on screen
/// starting east: E, NE, N, NW, W, SW, S, SE (image y grows downwards).
const DIRECTIONS: [(isize, isize); 8] = [
    (1, 0),
    (1, -1),
    (0, -1),
    (-1, -1),
    (-1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Chain code of "west", where an outer border's search starts.
const WEST: usize = 4;
/// Chain code of "east", where a hole border's search starts.
const EAST: usize = 0;

/// Marks written into the label image while following borders.
const UNVISITED: i8 = 1;
const VISITED: i8 = 2;
const RIGHT_BOUND: i8 = -2;

/// One traced border: its points `start..end`, whether it is a hole border,
/// and the padded index of the pixel whose raster-scan visit started it.
#[derive(Clone, Copy, Debug)]
struct Span {
    start: usize,
    end: usize,
    hole: bool,
    trigger: usize,
}

/// A binary image with a one-pixel zero frame, plus the contours traced on it.
/// Reused across thresholds (and windows) to avoid reallocating. The image
/// may be a window of a larger one: `origin` is added to every point.
pub struct ContourScanner {
    width: usize,
    height: usize,
    stride: usize,
    origin: [i32; 2],
    labels: Vec<i8>,
    offsets: [isize; 8],
    points: Vec<[i32; 2]>,
    spans: Vec<Span>,
    /// The diagonal steps of the last [`ContourScanner::outer_border_at`]
    /// walk (odd chain codes), the closing step included.
    diagonal_steps: usize,
}

impl Default for ContourScanner {
    /// A scanner for an empty image, to be sized by
    /// [`ContourScanner::clear`] or [`ContourScanner::reset_window`].
    fn default() -> Self {
        Self::new(0, 0)
    }
}

impl ContourScanner {
    /// A scanner for images of `width` x `height` pixels.
    pub fn new(width: usize, height: usize) -> Self {
        let stride = width + 2;
        let offsets = DIRECTIONS.map(|(dx, dy)| dx + dy * stride as isize);
        Self {
            width,
            height,
            stride,
            origin: [0, 0],
            labels: vec![0; stride * (height + 2)],
            offsets,
            points: Vec::new(),
            spans: Vec::new(),
            diagonal_steps: 0,
        }
    }

    /// Makes this a blank `width` x `height` window whose pixel (0, 0) is
    /// pixel `origin` of the full image (points are reported in full-image
    /// coordinates).
    pub fn reset_window(&mut self, width: usize, height: usize, origin: [i32; 2]) {
        self.width = width;
        self.height = height;
        self.stride = width + 2;
        self.origin = origin;
        self.offsets = DIRECTIONS.map(|(dx, dy)| dx + dy * self.stride as isize);
        self.labels.clear();
        self.labels.resize(self.stride * (height + 2), 0);
    }

    /// Makes pixels `x0..=x1` of row `y` of the current image (window
    /// coordinates) white (`value` 1) or background (0): a blank image of
    /// [`ContourScanner::reset_window`] filled run by run, or blanked again
    /// run by run (a border walk marks only white pixels).
    pub fn set_labels(&mut self, y: usize, x0: usize, x1: usize, value: i8) {
        let start = (y + 1) * self.stride + 1;
        self.labels[start + x0..=start + x1].fill(value);
    }

    /// Row `y` of the current image's labels (window coordinates), to be
    /// written whole as 1 (white) or 0 (background): a frame filled row
    /// by row needs no clearing (a border walk marks only white pixels).
    pub fn row_mut(&mut self, y: usize) -> &mut [i8] {
        let start = (y + 1) * self.stride + 1;
        &mut self.labels[start..start + self.width]
    }

    /// Makes this a blank (all zero) `width` x `height` image, reusing its
    /// buffers: the start of filling it run by run with
    /// [`ContourScanner::set_labels`].
    pub fn clear(&mut self, width: usize, height: usize) {
        self.reset_window(width, height, [0, 0]);
    }

    /// Follows the outer border that the raster scan would start at pixel
    /// (x, y), the first pixel of a white component in raster order, and
    /// returns its points: the contour [`ContourScanner::trace_all`] gives
    /// that component (its only one when it has no hole), found without
    /// the scan. Other contours traced before are forgotten. The walk
    /// writes no marks into the labels (only the raster scan reads them;
    /// every walk reads a label only as zero or not). Also returns how many
    /// of the border's steps, from each point to the next and from the last
    /// back to the first, are diagonal (the others are one pixel along an
    /// axis; a lone pixel has no step): its perimeter without a sum over
    /// the points (`shape::perimeter_of_steps`).
    pub fn outer_border_at(&mut self, x: usize, y: usize) -> (&[[i32; 2]], usize) {
        self.points.clear();
        self.spans.clear();
        self.diagonal_steps = 0;
        let at = (y + 1) * self.stride + x + 1;
        self.follow_border::<false>(at, WEST, at);
        (&self.points, self.diagonal_steps)
    }

    /// Binarises a window of grey levels (row-major, `width * height`,
    /// negative outside the component of interest): white where the value
    /// exceeds `level`, which must be at least -1.
    pub fn binarise_levels(&mut self, values: &[i16], level: i16) {
        for (y, row) in values
            .chunks_exact(self.width)
            .take(self.height)
            .enumerate()
        {
            let start = (y + 1) * self.stride + 1;
            let dst = &mut self.labels[start..start + self.width];
            for (d, &v) in dst.iter_mut().zip(row) {
                *d = i8::from(v > level);
            }
        }
    }

    /// Binarises `pixels` (row-major, `width * height` grey levels) with
    /// OpenCV's `THRESH_BINARY` rule for 8-bit images: white where the value
    /// exceeds `floor(threshold)`.
    pub fn binarise(&mut self, pixels: &[u8], threshold: f64) {
        let level = threshold.floor();
        for (y, row) in pixels
            .chunks_exact(self.width)
            .take(self.height)
            .enumerate()
        {
            let start = (y + 1) * self.stride + 1;
            let dst = &mut self.labels[start..start + self.width];
            for (d, &v) in dst.iter_mut().zip(row) {
                *d = i8::from(f64::from(v) > level);
            }
        }
    }

    /// Binarises `pixels` (row-major, `width * height`): white where the
    /// value exceeds `level` (at least -1), i.e. `THRESH_BINARY` at any
    /// threshold whose floor is `level`.
    #[cfg(test)]
    pub fn binarise_above(&mut self, pixels: &[u8], level: i16) {
        for (y, row) in pixels
            .chunks_exact(self.width)
            .take(self.height)
            .enumerate()
        {
            let start = (y + 1) * self.stride + 1;
            let dst = &mut self.labels[start..start + self.width];
            for (d, &v) in dst.iter_mut().zip(row) {
                *d = i8::from(i16::from(v) > level);
            }
        }
    }

    /// Whether pixel (x, y) is white in the current binary image.
    pub fn is_white(&self, x: usize, y: usize) -> bool {
        x < self.width && y < self.height && self.labels[(y + 1) * self.stride + x + 1] != 0
    }

    /// Traces every border of the current binary image; afterwards
    /// [`ContourScanner::contours`] yields them.
    ///
    /// The raster scan starts a border only where a pixel and its left
    /// neighbour differ in being zero (an outer border at a zero -> white
    /// step, a hole border at a white -> zero step), and border following
    /// never turns a zero label white or back, so the scan visits just those
    /// steps, found eight labels at a time; the labels there are read when
    /// the scan reaches them, as in a pixel-by-pixel scan.
    pub fn trace_all(&mut self) {
        self.points.clear();
        self.spans.clear();
        for y in 1..=self.height {
            let first = y * self.stride + 1;
            let end = first + self.width;
            // The padding left of the row is zero.
            let mut left_white = 0u64;
            let mut i = first;
            while i < end {
                let n = (end - i).min(8);
                if n == 8 && left_white == 0 && self.zero_word(i) {
                    // Eight zero labels after a zero one: no step.
                    i += 8;
                    continue;
                }
                let white = self.white_bytes(i, n);
                let mut steps = white ^ ((white << 8) | left_white);
                if n < 8 {
                    // No step at the padding after the row.
                    steps &= (1u64 << (8 * n)) - 1;
                }
                left_white = (white >> 56) & 0x80;
                while steps != 0 {
                    let at = i + (steps.trailing_zeros() / 8) as usize;
                    steps &= steps - 1;
                    let here = self.labels[at];
                    let left = self.labels[at - 1];
                    if here == UNVISITED && left == 0 {
                        self.follow_border::<true>(at, WEST, at);
                    } else if here == 0 && left >= UNVISITED {
                        self.follow_border::<true>(at - 1, EAST, at);
                    }
                }
                i += n;
            }
        }
    }

    /// Whether labels `i..i + 8` are all zero.
    fn zero_word(&self, i: usize) -> bool {
        let bytes: [i8; 8] = self.labels[i..i + 8].try_into().expect("eight labels");
        u64::from_ne_bytes(bytes.map(|b| b as u8)) == 0
    }

    /// Bit 8k + 7 set where label `i + k` is non-zero, for k < `n` (<= 8).
    fn white_bytes(&self, i: usize, n: usize) -> u64 {
        let mut bytes = [0u8; 8];
        if n == 8 {
            let word: [i8; 8] = self.labels[i..i + 8].try_into().expect("eight labels");
            bytes = word.map(|b| b as u8);
        } else {
            for (d, &l) in bytes.iter_mut().zip(&self.labels[i..i + n]) {
                *d = l as u8;
            }
        }
        let w = u64::from_le_bytes(bytes);
        const LOW: u64 = 0x7f7f_7f7f_7f7f_7f7f;
        // Per byte: low seven bits plus 0x7f carries into the top bit
        // unless they are zero (and never into the next byte).
        (((w & LOW) + LOW) | w) & !LOW
    }

    /// The traced contours, each a closed sequence of pixel coordinates, in
    /// OpenCV's order (the reverse of their discovery in raster order).
    #[cfg(test)]
    pub fn contours(&self) -> impl Iterator<Item = &[[i32; 2]]> {
        self.spans
            .iter()
            .rev()
            .map(|s| &self.points[s.start..s.end])
    }

    /// The traced contours in discovery order, each with the full-image
    /// (x, y) of the pixel whose raster-scan visit started it. Within one
    /// 8-connected component these pixels and contours are the same whether
    /// the component is traced alone or in the full image.
    pub fn contours_with_trigger(&self) -> impl Iterator<Item = ([i32; 2], &[[i32; 2]])> {
        self.spans
            .iter()
            .map(|s| (self.full_xy(s.trigger), &self.points[s.start..s.end]))
    }

    /// Like [`ContourScanner::contours`], only the outer borders of white
    /// components (no hole borders).
    pub fn outer_contours(&self) -> impl Iterator<Item = &[[i32; 2]]> {
        self.spans
            .iter()
            .rev()
            .filter(|s| !s.hole)
            .map(|s| &self.points[s.start..s.end])
    }

    /// Image size in pixels (width, height).
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    fn full_xy(&self, index: usize) -> [i32; 2] {
        let x = (index % self.stride) as i32 - 1 + self.origin[0];
        let y = (index / self.stride) as i32 - 1 + self.origin[1];
        [x, y]
    }

    fn push_point(&mut self, index: usize) {
        let xy = self.full_xy(index);
        self.points.push(xy);
    }

    fn step(&self, index: usize, direction: usize) -> usize {
        index.wrapping_add_signed(self.offsets[direction & 7])
    }

    /// Follows one border from `start`, whose neighbour in direction
    /// `empty_side` is background (west for outer borders, east for holes);
    /// `MARK`: whether the walk marks the labels for the raster scan.
    fn follow_border<const MARK: bool>(&mut self, start: usize, empty_side: usize, trigger: usize) {
        let first = self.points.len();
        match self.first_neighbour(start, empty_side) {
            None => {
                if MARK {
                    self.labels[start] = RIGHT_BOUND;
                }
                self.push_point(start);
            }
            Some((last, direction)) => self.walk::<MARK>(start, last, direction),
        }
        self.spans.push(Span {
            start: first,
            end: self.points.len(),
            hole: empty_side == EAST,
            trigger,
        });
    }

    /// Searches clockwise around `start` from `empty_side` for a white pixel:
    /// it is the last pixel of the border walk. `None` for an isolated pixel.
    fn first_neighbour(&self, start: usize, empty_side: usize) -> Option<(usize, usize)> {
        let mut direction = empty_side;
        loop {
            direction = (direction + 7) & 7;
            if direction == empty_side {
                return None;
            }
            let candidate = self.step(start, direction);
            if self.labels[candidate] != 0 {
                return Some((candidate, direction));
            }
        }
    }

    /// The border walk proper: at each pixel search counter-clockwise from the
    /// previous pixel for the next white one, until the walk is about to
    /// repeat its first move. With `MARK`, marks pixels whose east side was
    /// seen empty (and the others visited).
    fn walk<const MARK: bool>(&mut self, start: usize, last: usize, first_direction: usize) {
        let mut diagonal_steps = 0;
        let mut current = start;
        // Full-image coordinates of `current`, moved along with it.
        let mut xy = self.full_xy(start);
        let mut back = first_direction;
        loop {
            let mut direction = back;
            let next = loop {
                direction += 1;
                let candidate = self.step(current, direction);
                if self.labels[candidate] != 0 {
                    break candidate;
                }
            };
            direction &= 7;
            if MARK {
                if direction >= 1 && direction <= back {
                    self.labels[current] = RIGHT_BOUND;
                } else if self.labels[current] == UNVISITED {
                    self.labels[current] = VISITED;
                }
            }
            self.points.push(xy);
            if next == start && current == last {
                // Odd chain codes are the diagonal moves.
                self.diagonal_steps = diagonal_steps + (direction & 1);
                return;
            }
            current = next;
            let (dx, dy) = DIRECTIONS[direction];
            diagonal_steps += usize::from(dx != 0 && dy != 0);
            xy = [xy[0] + dx as i32, xy[1] + dy as i32];
            back = (direction + 4) & 7;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trace(width: usize, rows: &[&str]) -> Vec<Vec<[i32; 2]>> {
        let pixels: Vec<u8> = rows
            .iter()
            .flat_map(|r| r.bytes().map(|b| if b == b'#' { 255 } else { 0 }))
            .collect();
        let mut scanner = ContourScanner::new(width, rows.len());
        scanner.binarise(&pixels, 127.0);
        scanner.trace_all();
        scanner.contours().map(|c| c.to_vec()).collect()
    }

    #[test]
    fn isolated_pixel_is_a_one_point_contour() {
        let contours = trace(3, &["...", ".#.", "..."]);
        assert_eq!(contours, vec![vec![[1, 1]]]);
    }

    #[test]
    fn square_border_lists_every_boundary_pixel_once() {
        let contours = trace(5, &[".....", ".###.", ".###.", ".###.", "....."]);
        assert_eq!(contours.len(), 1);
        assert_eq!(contours[0].len(), 8);
        assert_eq!(contours[0][..4], [[1, 1], [1, 2], [1, 3], [2, 3]]);
    }

    #[test]
    fn ring_gives_outer_border_and_hole_border() {
        let contours = trace(5, &["#####", "#...#", "#...#", "#...#", "#####"]);
        // Values checked against cv2.findContours: hole first, corners skipped.
        assert_eq!(contours.len(), 2);
        assert_eq!(contours[0].len(), 12);
        assert_eq!(contours[0][..3], [[0, 1], [1, 0], [2, 0]]);
        assert_eq!(contours[1].len(), 16);
    }

    #[test]
    fn diagonal_pixels_form_one_component() {
        let contours = trace(4, &["#...", ".#..", "..#.", "...#"]);
        assert_eq!(contours.len(), 1);
        // A one-pixel-wide line is walked out and back.
        assert_eq!(contours[0].len(), 6);
    }
}
