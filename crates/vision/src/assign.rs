//! Sparse minimum-cost assignment (successive shortest augmenting paths with
//! dual potentials, i.e. the Hungarian / Jonker-Volgenant method run as
//! Dijkstra over candidate edges only). The pin tracker uses it to give each
//! reference pin at most one detected blob, so that a missing or extra blob
//! costs one "unassigned" and never shifts the order of the others.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// A candidate pairing of a row with column `col` at `cost`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    pub col: usize,
    pub cost: f64,
}

/// The optimal assignment: for each row its column, or `None` when leaving
/// the row unassigned was cheaper.
#[derive(Clone, Debug, PartialEq)]
pub struct Assignment {
    pub row_to_col: Vec<Option<usize>>,
    pub total_cost: f64,
}

const FREE: usize = usize::MAX;

/// Solves min sum of costs over matchings where every row takes one of its
/// candidate columns (each column at most once) or stays unassigned at
/// `unassigned_cost`. Edges with a non-finite cost, a cost not below
/// `unassigned_cost` or a column `>= n_cols` are ignored. O(rows x
/// explored edges x log) — near linear when candidates are local.
pub fn assign(n_cols: usize, rows: &[Vec<Edge>], unassigned_cost: f64) -> Assignment {
    let mut flat = EdgeRows::new();
    for row in rows {
        flat.edges.extend_from_slice(row);
        flat.end_row();
    }
    assign_rows(n_cols, &flat, unassigned_cost)
}

/// Candidate edges of every row stored in one buffer: row `r` is
/// `edges[starts[r]..starts[r + 1]]` (no allocation per row).
#[derive(Clone, Debug)]
pub(crate) struct EdgeRows {
    pub edges: Vec<Edge>,
    starts: Vec<usize>,
}

impl EdgeRows {
    pub fn new() -> Self {
        Self {
            edges: Vec::new(),
            starts: vec![0],
        }
    }

    /// Empty, with room for `rows` rows and `edges` edges.
    pub fn with_capacity(rows: usize, edges: usize) -> Self {
        let mut starts = Vec::with_capacity(rows + 1);
        starts.push(0);
        Self {
            edges: Vec::with_capacity(edges),
            starts,
        }
    }

    /// Closes the current row (the edges pushed since the last call).
    pub fn end_row(&mut self) {
        self.starts.push(self.edges.len());
    }

    pub fn len(&self) -> usize {
        self.starts.len() - 1
    }

    pub fn row(&self, r: usize) -> &[Edge] {
        &self.edges[self.starts[r]..self.starts[r + 1]]
    }
}

/// [`assign`] on rows stored flat.
pub(crate) fn assign_rows(n_cols: usize, rows: &EdgeRows, unassigned_cost: f64) -> Assignment {
    let unassigned_cost = if unassigned_cost.is_finite() {
        unassigned_cost
    } else {
        f64::MAX / 4.0
    };
    // Each row's valid edges plus its private "unassigned" column n_cols + row.
    let mut usable = EdgeRows::with_capacity(rows.len(), rows.edges.len() + rows.len());
    for r in 0..rows.len() {
        let valid = rows
            .row(r)
            .iter()
            .filter(|e| e.col < n_cols && e.cost.is_finite() && e.cost < unassigned_cost);
        usable.edges.extend(valid);
        usable.edges.push(Edge {
            col: n_cols + r,
            cost: unassigned_cost,
        });
        usable.end_row();
    }
    let row_col = distinct_unique_minima(n_cols, &usable).unwrap_or_else(|| solve(n_cols, &usable));
    assignment(&usable, &row_col, n_cols)
}

/// The optimal columns for rows already in the solver's form: every edge
/// valid (column below `n_cols`, finite cost below the row's last edge),
/// each row ending with its own "unassigned" column `n_cols + row` at the
/// finite unassigned cost. Same columns as [`assign_rows`] on the rows
/// without their last edges; no copy.
pub(crate) fn assign_usable(n_cols: usize, usable: &EdgeRows) -> Vec<Option<usize>> {
    let row_col = distinct_unique_minima(n_cols, usable).unwrap_or_else(|| solve(n_cols, usable));
    row_col.iter().map(|&c| (c < n_cols).then_some(c)).collect()
}

/// Each row's column (its own "unassigned" column is `n_cols + row`) by
/// successive shortest paths, rows in order.
fn solve(n_cols: usize, usable: &EdgeRows) -> Vec<usize> {
    solve_with(n_cols, usable, true)
}

/// [`solve`], optionally without the search-free first step.
fn solve_with(n_cols: usize, usable: &EdgeRows, direct: bool) -> Vec<usize> {
    let mut solver = Solver::new(n_cols + usable.len(), usable);
    solver.direct = direct;
    for row in 0..usable.len() {
        solver.augment_from(row);
    }
    solver.row_col
}

/// Each row's cheapest column, when every row has a single cheapest one
/// and no column is the cheapest of two rows: then each row at its own
/// minimum is the unique optimum, and the solver below returns exactly it
/// (every row's first Dijkstra pop is its cheapest column, at reduced cost
/// 0, still free; no potential changes). `None` otherwise.
fn distinct_unique_minima(n_cols: usize, rows: &EdgeRows) -> Option<Vec<usize>> {
    let mut taken = vec![false; n_cols];
    let mut row_col = Vec::with_capacity(rows.len());
    for r in 0..rows.len() {
        let (mut best, mut col, mut tie) = (f64::INFINITY, FREE, false);
        for e in rows.row(r) {
            if e.cost < best {
                (best, col, tie) = (e.cost, e.col, false);
            } else if e.cost == best {
                tie = true;
            }
        }
        if tie || col == FREE {
            return None;
        }
        if col < n_cols {
            if taken[col] {
                return None;
            }
            taken[col] = true;
        }
        row_col.push(col);
    }
    Some(row_col)
}

/// The assignment for each row's column `row_col` (columns `>= n_cols`
/// are the rows' own "unassigned" columns), with its total cost.
fn assignment(rows: &EdgeRows, row_col: &[usize], n_cols: usize) -> Assignment {
    let mut total_cost = 0.0;
    let row_to_col = row_col
        .iter()
        .enumerate()
        .map(|(r, &col)| {
            let row = rows.row(r);
            total_cost += row.iter().find(|e| e.col == col).map_or(0.0, |e| e.cost);
            (col < n_cols).then_some(col)
        })
        .collect();
    Assignment {
        row_to_col,
        total_cost,
    }
}

/// Heap entry ordered so that `BinaryHeap` pops the smallest distance.
#[derive(PartialEq)]
struct Pending(f64, usize);

impl Eq for Pending {}

impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Pending {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

/// Dual potentials and the current matching. Reduced costs
/// `cost - row_pot - col_pot` stay >= 0 and are 0 on matched edges.
struct Solver<'a> {
    edges: &'a EdgeRows,
    row_pot: Vec<f64>,
    col_pot: Vec<f64>,
    owner: Vec<usize>,
    row_col: Vec<usize>,
    dist: Vec<f64>,
    via_row: Vec<usize>,
    done: Vec<bool>,
    touched: Vec<usize>,
    settled: Vec<usize>,
    heap: BinaryHeap<Pending>,
    /// Take a row's nearest column without a search when it is free.
    direct: bool,
}

impl<'a> Solver<'a> {
    fn new(n_cols: usize, edges: &'a EdgeRows) -> Self {
        let row_pot = (0..edges.len())
            .map(|r| {
                edges
                    .row(r)
                    .iter()
                    .map(|e| e.cost)
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        Self {
            edges,
            row_pot,
            col_pot: vec![0.0; n_cols],
            owner: vec![FREE; n_cols],
            row_col: vec![FREE; edges.len()],
            dist: vec![f64::INFINITY; n_cols],
            via_row: vec![FREE; n_cols],
            done: vec![false; n_cols],
            touched: Vec::new(),
            settled: Vec::new(),
            heap: BinaryHeap::new(),
            direct: true,
        }
    }

    /// Dijkstra from the free row `start` to the nearest free column, then
    /// potential update and augmentation along the path.
    fn augment_from(&mut self, start: usize) {
        if self.direct && self.take_nearest_free(start) {
            return;
        }
        self.reset();
        self.relax_row(start, 0.0);
        let sink = loop {
            let Some(Pending(d, col)) = self.heap.pop() else {
                return; // unreachable: the row's own unassigned column is free
            };
            if self.done[col] || d > self.dist[col] {
                continue;
            }
            self.done[col] = true;
            if self.owner[col] == FREE {
                break col;
            }
            self.settled.push(col);
            self.relax_row(self.owner[col], d);
        };
        self.update_potentials(start, self.dist[sink]);
        self.flip_path(start, sink);
    }

    /// The search's first step without the heap: when the row's smallest
    /// reduced cost (ties to the smaller column, the heap's order) is at a
    /// free column, the search would end there at once; assign it, with
    /// the same potential update. False (nothing changed) otherwise. The
    /// search's scratch is left alone (the next search resets its own).
    fn take_nearest_free(&mut self, start: usize) -> bool {
        let mut best: Option<(f64, usize)> = None;
        for e in self.edges.row(start) {
            let d = 0.0 + e.cost - self.row_pot[start] - self.col_pot[e.col];
            if d.is_nan() || d == f64::INFINITY {
                continue; // never queued
            }
            let nearer = best.is_none_or(|(bd, bc)| d.total_cmp(&bd).then(e.col.cmp(&bc)).is_lt());
            if nearer {
                best = Some((d, e.col));
            }
        }
        match best {
            Some((d, col)) if self.owner[col] == FREE => {
                self.row_pot[start] += d;
                self.row_col[start] = col;
                self.owner[col] = start;
                true
            }
            _ => false,
        }
    }

    fn reset(&mut self) {
        for &c in &self.touched {
            self.dist[c] = f64::INFINITY;
            self.done[c] = false;
            self.via_row[c] = FREE;
        }
        self.touched.clear();
        self.settled.clear();
        self.heap.clear();
    }

    fn relax_row(&mut self, row: usize, base: f64) {
        let edges = self.edges;
        for e in edges.row(row) {
            if self.done[e.col] {
                continue;
            }
            let d = base + e.cost - self.row_pot[row] - self.col_pot[e.col];
            if d < self.dist[e.col] {
                if self.dist[e.col].is_infinite() {
                    self.touched.push(e.col);
                }
                self.dist[e.col] = d;
                self.via_row[e.col] = row;
                self.heap.push(Pending(d, e.col));
            }
        }
    }

    fn update_potentials(&mut self, start: usize, delta: f64) {
        self.row_pot[start] += delta;
        for &col in &self.settled {
            let gain = delta - self.dist[col];
            self.col_pot[col] -= gain;
            self.row_pot[self.owner[col]] += gain;
        }
    }

    fn flip_path(&mut self, start: usize, sink: usize) {
        let mut col = sink;
        loop {
            let row = self.via_row[col];
            let previous = self.row_col[row];
            self.row_col[row] = col;
            self.owner[col] = row;
            if row == start {
                return;
            }
            col = previous;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn dense(costs: &[Vec<f64>]) -> Vec<Vec<Edge>> {
        costs
            .iter()
            .map(|row| {
                row.iter()
                    .enumerate()
                    .map(|(col, &cost)| Edge { col, cost })
                    .collect()
            })
            .collect()
    }

    /// Exhaustive minimum over all injective row -> column maps (and skips).
    fn brute_force(costs: &[Vec<f64>], skip: f64, row: usize, used: &mut Vec<bool>) -> f64 {
        if row == costs.len() {
            return 0.0;
        }
        let mut best = skip + brute_force(costs, skip, row + 1, used);
        for col in 0..used.len() {
            if !used[col] && costs[row][col] < skip {
                used[col] = true;
                best = best.min(costs[row][col] + brute_force(costs, skip, row + 1, used));
                used[col] = false;
            }
        }
        best
    }

    #[test]
    fn matches_brute_force_on_random_problems() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for trial in 0..200 {
            let rows = rng.random_range(1..6);
            let cols = rng.random_range(1..7);
            let costs: Vec<Vec<f64>> = (0..rows)
                .map(|_| (0..cols).map(|_| rng.random_range(0.0..10.0)).collect())
                .collect();
            let skip = rng.random_range(1.0..12.0);
            let got = assign(cols, &dense(&costs), skip);
            let want = brute_force(&costs, skip, 0, &mut vec![false; cols]);
            assert!(
                (got.total_cost - want).abs() < 1e-9,
                "trial {trial}: {} vs {want}",
                got.total_cost
            );
            let skipped = got.row_to_col.iter().filter(|c| c.is_none()).count();
            let used: Vec<usize> = got.row_to_col.iter().flatten().copied().collect();
            let mut unique = used.clone();
            unique.sort_unstable();
            unique.dedup();
            assert_eq!(unique.len(), used.len(), "a column used twice");
            assert!(skipped <= rows);
        }
    }

    /// The direct first steps and, where every row's cheapest column is its
    /// own, the whole-problem shortcut give exactly the full search's
    /// answer; sparse local problems like the tracker's, with and without
    /// conflicts (and exact ties: costs on a coarse grid half the time).
    #[test]
    fn shortcuts_equal_the_full_search() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let mut shortcuts = 0;
        for _ in 0..300 {
            let n = rng.random_range(1..30);
            let spread = rng.random_range(0.0..0.9);
            let coarse = rng.random_bool(0.5);
            let jitter = |rng: &mut ChaCha8Rng| {
                let v: f64 = rng.random_range(-spread..spread);
                if coarse {
                    (v * 4.0).round() / 4.0
                } else {
                    v
                }
            };
            let cols: Vec<f64> = (0..n).map(|c| c as f64 + jitter(&mut rng)).collect();
            let mut usable = EdgeRows::new();
            for r in 0..n {
                let at = r as f64 + jitter(&mut rng);
                for (c, &x) in cols.iter().enumerate() {
                    let cost = (x - at).powi(2);
                    if cost < 4.0 && rng.random_bool(0.9) {
                        usable.edges.push(Edge { col: c, cost });
                    }
                }
                usable.edges.push(Edge {
                    col: n + r,
                    cost: 4.0,
                });
                usable.end_row();
            }
            let searched = solve_with(n, &usable, false);
            assert_eq!(solve(n, &usable), searched, "direct first steps");
            if let Some(fast) = distinct_unique_minima(n, &usable) {
                shortcuts += 1;
                assert_eq!(fast, searched);
            }
        }
        assert!(shortcuts > 50, "{shortcuts}");
    }

    #[test]
    fn prefers_the_globally_cheaper_pairing() {
        // Greedy would give row 0 column 0 (cost 1) and row 1 column 1 (100).
        let costs = vec![vec![1.0, 2.0], vec![2.0, 100.0]];
        let got = assign(2, &dense(&costs), 1000.0);
        assert_eq!(got.row_to_col, vec![Some(1), Some(0)]);
        assert!((got.total_cost - 4.0).abs() < 1e-12);
    }

    #[test]
    fn bad_edges_are_ignored() {
        let rows = vec![vec![
            Edge { col: 5, cost: 0.0 },
            Edge {
                col: 0,
                cost: f64::NAN,
            },
        ]];
        let got = assign(1, &rows, 3.0);
        assert_eq!(got.row_to_col, vec![None]);
        assert_eq!(assign(0, &[], 1.0).row_to_col, Vec::<Option<usize>>::new());
    }
}
