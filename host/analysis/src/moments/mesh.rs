//! Scattered samples in a plane made a surface: linear over their Delaunay
//! triangulation (`spade`), which fills the gaps between samples as the
//! paper's interpolation did (§6.A used Matlab's cubic `griddata`; linear
//! pieces can be integrated exactly, so the moments do not depend on a
//! resampling grid). [`Mesh::lobe`] cuts out the connected part above a
//! threshold that holds a point, each triangle clipped along the
//! threshold's iso-line.

use anyhow::{bail, Result};
use spade::{DelaunayTriangulation, Point2, Triangulation};
use std::collections::HashMap;

/// A corner: position and value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    pub p: [f64; 2],
    pub f: f64,
}

impl Node {
    /// The area of the triangle `c`.
    pub fn area(c: &[Node; 3]) -> f64 {
        let [a, b, d] = c.map(|n| n.p);
        ((b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1])).abs() / 2.0
    }
}

pub struct Mesh {
    nodes: Vec<Node>,
    faces: Vec<[usize; 3]>,
}

/// The part of the surface at or above a threshold that holds a point.
pub struct Lobe {
    /// Triangles whose value is linear between their corners.
    pub pieces: Vec<[Node; 3]>,
    /// Samples at or above the threshold within it.
    pub samples: usize,
    /// Whether it reaches the edge of the sampled domain above the
    /// threshold: its moments are then those of a truncated lobe.
    pub truncated: bool,
    /// Every edge with an end at or above the threshold, as the vector
    /// between its ends: the stretches the surface is interpolated across
    /// within the lobe or to its outline (a sampling gap, such as the head's
    /// blind zone, shows here).
    pub edges: Vec<[f64; 2]>,
}

impl Mesh {
    /// Samples at one position (to 1e-9) are averaged into one node.
    pub fn new(samples: impl IntoIterator<Item = Node>) -> Result<Mesh> {
        let mut at: HashMap<(i64, i64), (usize, f64, Node)> = HashMap::new();
        for (k, s) in samples.into_iter().enumerate() {
            let key = (s.p[0] * 1e9).round() as i64;
            let e = at
                .entry((key, (s.p[1] * 1e9).round() as i64))
                .or_insert((k, 0.0, Node { p: s.p, f: 0.0 }));
            e.1 += 1.0;
            e.2.f += s.f;
        }
        let mut nodes: Vec<(usize, Node)> = at.into_values().map(|(k, n, s)| (k, Node { f: s.f / n, ..s })).collect();
        nodes.sort_by_key(|(k, _)| *k);
        let nodes: Vec<Node> = nodes.into_iter().map(|(_, n)| n).collect();
        if nodes.len() < 3 {
            bail!("{} distinct directions: a surface needs three", nodes.len());
        }
        let points = nodes.iter().map(|n| Point2::new(n.p[0], n.p[1])).collect();
        let t = DelaunayTriangulation::<Point2<f64>>::bulk_load_stable(points)
            .map_err(|e| anyhow::anyhow!("triangulating the samples: {e:?}"))?;
        let faces: Vec<[usize; 3]> = t.inner_faces().map(|f| f.vertices().map(|v| v.index())).collect();
        if faces.is_empty() {
            bail!("the samples lie on one line: no surface between them");
        }
        Ok(Mesh { nodes, faces })
    }

    fn corners(&self, face: usize) -> [Node; 3] {
        self.faces[face].map(|k| self.nodes[k])
    }

    /// The face holding `p` and the value there, or `None` outside the
    /// samples' convex hull.
    pub fn at(&self, p: [f64; 2]) -> Option<(usize, f64)> {
        (0..self.faces.len()).find_map(|k| {
            let c = self.corners(k);
            let w = barycentric(&c, p)?;
            Some((k, w[0] * c[0].f + w[1] * c[1].f + w[2] * c[2].f))
        })
    }

    /// The connected part at or above `t` around face `seed`: faces join
    /// across an edge with an end at or above `t` (below on both ends, the
    /// linear value is below all along it).
    pub fn lobe(&self, seed: usize, t: f64) -> Lobe {
        let mut sides: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        for (k, f) in self.faces.iter().enumerate() {
            for e in edges(f) {
                sides.entry(e).or_default().push(k);
            }
        }
        let above = |k: usize| self.nodes[k].f >= t;
        let mut seen = vec![false; self.faces.len()];
        let mut todo = vec![seed];
        seen[seed] = true;
        let (mut pieces, mut truncated, mut spans) = (Vec::new(), false, Vec::new());
        let mut samples: Vec<usize> = Vec::new();
        while let Some(k) = todo.pop() {
            pieces.extend(clip(&self.corners(k), t));
            samples.extend(self.faces[k].iter().copied().filter(|&v| above(v)));
            for e in edges(&self.faces[k]) {
                if !(above(e.0) || above(e.1)) {
                    continue;
                }
                let (a, b) = (self.nodes[e.0].p, self.nodes[e.1].p);
                spans.push([b[0] - a[0], b[1] - a[1]]);
                let across = &sides[&e];
                truncated |= across.len() == 1;
                for &n in across {
                    if !seen[n] {
                        seen[n] = true;
                        todo.push(n);
                    }
                }
            }
        }
        samples.sort_unstable();
        samples.dedup();
        Lobe {
            pieces,
            samples: samples.len(),
            truncated,
            edges: spans,
        }
    }
}

fn edges(f: &[usize; 3]) -> [(usize, usize); 3] {
    let e = |a: usize, b: usize| (a.min(b), a.max(b));
    [e(f[0], f[1]), e(f[1], f[2]), e(f[2], f[0])]
}

/// `p`'s barycentric weights in the triangle, if it lies inside or on it.
fn barycentric(c: &[Node; 3], p: [f64; 2]) -> Option<[f64; 3]> {
    let [a, b, d] = c.map(|n| n.p);
    let det = (b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1]);
    if det == 0.0 {
        return None;
    }
    let w1 = ((p[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (p[1] - a[1])) / det;
    let w2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
    let w = [1.0 - w1 - w2, w1, w2];
    const ON: f64 = -1e-12;
    w.iter().all(|&x| x >= ON).then_some(w)
}

/// The part of a linear triangle at or above `t`, as triangles (none, one
/// or two: a triangle cut by a line is a triangle or a quadrilateral).
fn clip(c: &[Node; 3], t: f64) -> Vec<[Node; 3]> {
    let mut poly: Vec<Node> = Vec::with_capacity(4);
    for k in 0..3 {
        let (a, b) = (c[k], c[(k + 1) % 3]);
        if a.f >= t {
            poly.push(a);
        }
        if (a.f >= t) != (b.f >= t) {
            let s = (t - a.f) / (b.f - a.f);
            poly.push(Node {
                p: [a.p[0] + s * (b.p[0] - a.p[0]), a.p[1] + s * (b.p[1] - a.p[1])],
                f: t,
            });
        }
    }
    (1..poly.len().saturating_sub(1)).map(|k| [poly[0], poly[k], poly[k + 1]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(f: impl Fn(f64, f64) -> f64) -> Mesh {
        let mut s = Vec::new();
        for i in -20..=20 {
            for j in -20..=20 {
                let p = [i as f64 * 0.5, j as f64 * 0.5];
                s.push(Node { p, f: f(p[0], p[1]) });
            }
        }
        Mesh::new(s).unwrap()
    }

    #[test]
    fn a_cone_is_cut_to_a_disc_of_its_level() {
        // f = 5 − r: the part ≥ 2 is the disc r ≤ 3, area 9π, far from the edge.
        let m = grid(|x, y| 5.0 - x.hypot(y));
        let (seed, f0) = m.at([0.0, 0.0]).unwrap();
        assert!((f0 - 5.0).abs() < 1e-12);
        let lobe = m.lobe(seed, 2.0);
        let area: f64 = lobe.pieces.iter().map(Node::area).sum();
        assert!((area / (9.0 * std::f64::consts::PI) - 1.0).abs() < 0.01, "{area}");
        assert!(!lobe.truncated);
        // Grid edges 0.5, diagonals 0.71.
        let longest = lobe.edges.iter().map(|e| e[0].hypot(e[1])).fold(0.0, f64::max);
        assert!((longest - 0.5f64.hypot(0.5)).abs() < 1e-9, "{longest}");
        assert!(lobe.pieces.iter().flatten().all(|n| n.f >= 2.0 - 1e-12));
    }

    #[test]
    fn two_peaks_apart_are_two_lobes_and_the_edge_is_found() {
        let m = grid(|x, y| if x < -2.0 { 3.0 } else if x > 2.0 { 4.0 } else { 0.0 } + 0.0 * y);
        let (left, _) = m.at([-5.0, 0.0]).unwrap();
        let lobe = m.lobe(left, 1.0);
        assert!(lobe.pieces.iter().flatten().all(|n| n.p[0] < -1.0));
        assert!(lobe.truncated);
        assert!(m.at([20.0, 0.0]).is_none());
        assert!(Mesh::new([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]].map(|p| Node { p, f: 1.0 })).is_err());
    }
}
