//! The shortest open path through a set of points from a fixed start, by
//! local search: a nearest-neighbour path improved by 2-opt and Or-opt moves
//! until neither finds a gain.
//!
//! Why hand-written: the crates for the travelling salesman problem solve
//! closed tours over a stored distance matrix; ours is an open path (the
//! scan ends wherever it ends) whose costs are move times computed on
//! demand, and 4 096 points would need a 128 MiB matrix of f64. Candidate moves are
//! restricted to each point's nearest neighbours by cost, the usual
//! neighbour-list speed-up (Johnson & McGeoch, "The TSP: a case study in
//! local optimization", 1997).

/// Neighbours per node that the moves consider.
const NEIGHBOURS: usize = 10;
/// Longest chain of points an Or-opt move relocates.
const OR_SEGMENT: usize = 3;
/// Gains below this (s) are noise of the floating-point sums.
const EPS: f64 = 1e-9;
/// Passes of both moves at most (each pass is a full sweep; convergence
/// usually takes a handful).
const MAX_PASSES: usize = 50;

/// The visit order of nodes `1..=n` (node 0 is the fixed start) that the
/// search reaches, with `cost(a, b)` the cost of going from node `a` to node
/// `b` (symmetric). Returned without the start.
pub fn shortest_path(n: usize, cost: impl Fn(usize, usize) -> f64) -> Vec<usize> {
    if n == 0 {
        return Vec::new();
    }
    let near = neighbour_lists(n, &cost);
    let mut path = Path::nearest_neighbour(n, &cost);
    for _ in 0..MAX_PASSES {
        let a = path.two_opt(&near, &cost);
        let b = path.or_opt(&near, &cost);
        if !(a || b) {
            break;
        }
    }
    path.nodes.split_off(1)
}

/// The `NEIGHBOURS` cheapest other nodes of every node, cheapest first; one
/// row of costs at a time, so memory stays linear in the nodes.
fn neighbour_lists(n: usize, cost: &impl Fn(usize, usize) -> f64) -> Vec<Vec<usize>> {
    let mut row: Vec<(f64, usize)> = Vec::with_capacity(n);
    let order = |x: &(f64, usize), y: &(f64, usize)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
    (0..=n)
        .map(|a| {
            row.clear();
            row.extend((0..=n).filter(|&b| b != a).map(|b| (cost(a, b), b)));
            if NEIGHBOURS < row.len() {
                row.select_nth_unstable_by(NEIGHBOURS, order);
                row.truncate(NEIGHBOURS);
            }
            row.sort_by(order);
            row.iter().map(|&(_, b)| b).collect()
        })
        .collect()
}

/// A path from node 0 and where each node sits on it.
struct Path {
    nodes: Vec<usize>,
    at: Vec<usize>,
}

impl Path {
    fn nearest_neighbour(n: usize, cost: &impl Fn(usize, usize) -> f64) -> Self {
        let mut open: Vec<usize> = (1..=n).collect();
        let mut nodes = vec![0];
        while !open.is_empty() {
            let last = nodes[nodes.len() - 1];
            let (mut best, mut best_cost) = (0, cost(last, open[0]));
            for (k, &b) in open.iter().enumerate().skip(1) {
                let c = cost(last, b);
                if c < best_cost {
                    (best, best_cost) = (k, c);
                }
            }
            // Keeps the ties in index order, so the plan is deterministic.
            nodes.push(open.remove(best));
        }
        let mut path = Path { at: vec![0; n + 1], nodes };
        path.reindex(0..=n);
        path
    }

    fn reindex(&mut self, range: impl Iterator<Item = usize>) {
        for k in range {
            self.at[self.nodes[k]] = k;
        }
    }

    /// Cost of the edge leaving position `k`: nothing past the end.
    fn leaving(&self, k: usize, cost: &impl Fn(usize, usize) -> f64) -> f64 {
        self.nodes.get(k + 1).map_or(0.0, |&b| cost(self.nodes[k], b))
    }

    /// Cost from node `a` to the node at position `k`: nothing past the end.
    fn to_position(&self, a: usize, k: usize, cost: &impl Fn(usize, usize) -> f64) -> f64 {
        self.nodes.get(k).map_or(0.0, |&b| cost(a, b))
    }

    /// One sweep of 2-opt moves (reversing a stretch of the path); whether
    /// any was made.
    fn two_opt(&mut self, near: &[Vec<usize>], cost: &impl Fn(usize, usize) -> f64) -> bool {
        let mut improved = false;
        for i in 0..self.nodes.len() - 1 {
            let (a, b) = (self.nodes[i], self.nodes[i + 1]);
            // Edges (a, b) and (c, e) become (a, c) and (b, e), reversing b..=c.
            for &c in &near[a] {
                let j = self.at[c];
                if j <= i + 1 {
                    continue;
                }
                let gain = cost(a, b) + self.leaving(j, cost) - cost(a, c) - self.to_position(b, j + 1, cost);
                if gain > EPS {
                    self.nodes[i + 1..=j].reverse();
                    self.reindex(i + 1..=j);
                    improved = true;
                    break;
                }
            }
            let (a, b) = (self.nodes[i], self.nodes[i + 1]);
            // Edges (p, c) and (a, b), c before a, become (p, a) and (c, b),
            // reversing c..=a.
            for &c in &near[b] {
                let j = self.at[c];
                if j == 0 || j > i {
                    continue;
                }
                let p = self.nodes[j - 1];
                let gain = cost(p, c) + cost(a, b) - cost(p, a) - cost(c, b);
                if gain > EPS {
                    self.nodes[j..=i].reverse();
                    self.reindex(j..=i);
                    improved = true;
                    break;
                }
            }
        }
        improved
    }

    /// One sweep of Or-opt moves (a chain of up to `OR_SEGMENT` points moved
    /// elsewhere, either way round); whether any was made.
    fn or_opt(&mut self, near: &[Vec<usize>], cost: &impl Fn(usize, usize) -> f64) -> bool {
        let mut improved = false;
        for len in 1..=OR_SEGMENT {
            let mut s = 1;
            while s + len <= self.nodes.len() {
                if self.relocate(s, len, near, cost) {
                    improved = true;
                } else {
                    s += 1;
                }
            }
        }
        improved
    }

    /// Moves the chain at positions `s..s + len` to the best place next to a
    /// neighbour of its ends, if that shortens the path.
    fn relocate(&mut self, s: usize, len: usize, near: &[Vec<usize>], cost: &impl Fn(usize, usize) -> f64) -> bool {
        let (first, last) = (self.nodes[s], self.nodes[s + len - 1]);
        let p = self.nodes[s - 1];
        let removed = cost(p, first) + self.leaving(s + len - 1, cost) - self.to_position(p, s + len, cost);
        if removed <= EPS {
            return false;
        }
        // Insert after position q, between q and q + 1, not touching the chain.
        let mut best: Option<(f64, usize, bool)> = None;
        for &c in near[first].iter().chain(&near[last]) {
            let k = self.at[c];
            for q in [k.wrapping_sub(1), k] {
                if q >= self.nodes.len() || (s - 1..s + len).contains(&q) {
                    continue;
                }
                let x = self.nodes[q];
                let old = self.leaving(q, cost);
                for reversed in [false, true] {
                    let (head, tail) = if reversed { (last, first) } else { (first, last) };
                    let added = cost(x, head) + self.to_position(tail, q + 1, cost) - old;
                    let gain = removed - added;
                    if gain > EPS && best.is_none_or(|(g, _, _)| gain > g) {
                        best = Some((gain, q, reversed));
                    }
                }
            }
        }
        let Some((_, q, reversed)) = best else { return false };
        let mut chain: Vec<usize> = self.nodes.drain(s..s + len).collect();
        if reversed {
            chain.reverse();
        }
        let at = if q < s { q + 1 } else { q + 1 - len };
        self.nodes.splice(at..at, chain);
        self.reindex(0..self.nodes.len());
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn length(path: &[usize], cost: &impl Fn(usize, usize) -> f64) -> f64 {
        core::iter::once(0)
            .chain(path.iter().copied())
            .collect::<Vec<_>>()
            .windows(2)
            .map(|e| cost(e[0], e[1]))
            .sum()
    }

    /// Start inside a line of points: the short way goes to the near end
    /// first, the greedy path runs off to the far end and comes back.
    #[test]
    fn a_line_from_its_middle_goes_to_the_near_end_first() {
        let xs: [f64; 6] = [0.0, 1.0, -1.5, 2.0, 3.0, 4.0];
        let cost = |a: usize, b: usize| (xs[a] - xs[b]).abs();
        let greedy = Path::nearest_neighbour(xs.len() - 1, &cost).nodes.split_off(1);
        assert_eq!(length(&greedy, &cost), 9.5);
        let path = shortest_path(xs.len() - 1, cost);
        assert_eq!(path, vec![2, 1, 3, 4, 5]);
        assert_eq!(length(&path, &cost), 7.0);
    }

    /// A grid from beside a corner: every point once, in unit steps (the optimum).
    #[test]
    fn a_grid_is_walked_in_unit_steps() {
        let (w, h) = (9usize, 7usize);
        let xy = |k: usize| {
            if k == 0 {
                (-1.0, 0.0)
            } else {
                (((k - 1) % w) as f64, ((k - 1) / w) as f64)
            }
        };
        let cost = |a: usize, b: usize| {
            let (p, q) = (xy(a), xy(b));
            ((p.0 - q.0) * (p.0 - q.0) + (p.1 - q.1) * (p.1 - q.1)).sqrt()
        };
        let path = shortest_path(w * h, cost);
        let mut sorted = path.clone();
        sorted.sort();
        assert_eq!(sorted, (1..=w * h).collect::<Vec<_>>());
        assert!(length(&path, &cost) <= (w * h) as f64 + 1e-9);
    }

    /// Random points: a permutation, never longer than the greedy path, and
    /// shorter on this draw.
    #[test]
    fn random_points_beat_the_greedy_path() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let pts: Vec<(f64, f64)> = (0..300).map(|_| (next(), next())).collect();
        let cost = |a: usize, b: usize| ((pts[a].0 - pts[b].0).powi(2) + (pts[a].1 - pts[b].1).powi(2)).sqrt();
        let greedy = Path::nearest_neighbour(pts.len() - 1, &cost).nodes.split_off(1);
        let path = shortest_path(pts.len() - 1, cost);
        let mut sorted = path.clone();
        sorted.sort();
        assert_eq!(sorted, (1..pts.len()).collect::<Vec<_>>());
        assert!(length(&path, &cost) < 0.95 * length(&greedy, &cost));
    }
}
