//! `maze`: a 7×7-cell labyrinth under a ceiling, lit by 13 small ceiling lamps;
//! the camera walks the corridor from the entrance cell to the farthest cell.
//! Walls come from a depth-first maze carved with a fixed seed.

use super::{Builtin, ceiling_lamp, horizontal, walk};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::rng::{Purpose, stream};
use glam::Vec3;

const N: usize = 7;
const CELL: f32 = 3.0;
const H: f32 = 3.0;

pub fn build() -> Builtin {
    // Carve: walls[(cell, dir)] open after DFS. dir 0: +x, 1: +z.
    let mut open_x = [[false; N]; N]; // wall between (i, j) and (i+1, j)
    let mut open_z = [[false; N]; N]; // wall between (i, j) and (i, j+1)
    let mut seen = [[false; N]; N];
    let mut parent = [[None; N]; N];
    let mut rng = stream(7, 0, Purpose::SCENE, 1);
    let mut stack = vec![(0usize, 0usize)];
    seen[0][0] = true;
    while let Some(&(i, j)) = stack.last() {
        let mut nb = Vec::new();
        if i + 1 < N && !seen[i + 1][j] {
            nb.push((i + 1, j));
        }
        if i > 0 && !seen[i - 1][j] {
            nb.push((i - 1, j));
        }
        if j + 1 < N && !seen[i][j + 1] {
            nb.push((i, j + 1));
        }
        if j > 0 && !seen[i][j - 1] {
            nb.push((i, j - 1));
        }
        if nb.is_empty() {
            stack.pop();
            continue;
        }
        let (a, b) = nb[rng.below(nb.len() as u32) as usize];
        if a != i {
            open_x[i.min(a)][j] = true
        } else {
            open_z[i][j.min(b)] = true
        }
        seen[a][b] = true;
        parent[a][b] = Some((i, j));
        stack.push((a, b));
    }
    let materials = vec![
        Material::diffuse("floor", Vec3::new(0.45, 0.42, 0.38)),
        Material::diffuse("wall", Vec3::new(0.75, 0.7, 0.6)),
        Material::diffuse("ceiling", Vec3::new(0.6, 0.6, 0.6)),
        Material::emissive("lamp", Vec3::splat(0.8), Vec3::new(40.0, 36.0, 30.0)),
    ];
    let (floor, wall, ceil, lamp) = (0, 1, 2, 3);
    let mut mesh = Mesh::default();
    let size = N as f32 * CELL;
    horizontal(&mut mesh, (0.0, size), (0.0, size), 0.0, true, floor);
    horizontal(&mut mesh, (0.0, size), (0.0, size), H, false, ceil);
    // Outer walls and closed inner walls, as thin boxes 0.2 m thick.
    let t = 0.1;
    let wall_box = |mesh: &mut Mesh, lo: Vec3, hi: Vec3| mesh.push_box(lo, hi, wall, true);
    wall_box(&mut mesh, Vec3::new(-t, 0.0, -t), Vec3::new(t, H, size + t));
    wall_box(&mut mesh, Vec3::new(size - t, 0.0, -t), Vec3::new(size + t, H, size + t));
    wall_box(&mut mesh, Vec3::new(-t, 0.0, -t), Vec3::new(size + t, H, t));
    wall_box(&mut mesh, Vec3::new(-t, 0.0, size - t), Vec3::new(size + t, H, size + t));
    for i in 0..N {
        for j in 0..N {
            let (x0, z0) = (i as f32 * CELL, j as f32 * CELL);
            if i + 1 < N && !open_x[i][j] {
                wall_box(&mut mesh, Vec3::new(x0 + CELL - t, 0.0, z0 - t), Vec3::new(x0 + CELL + t, H, z0 + CELL + t));
            }
            if j + 1 < N && !open_z[i][j] {
                wall_box(&mut mesh, Vec3::new(x0 - t, 0.0, z0 + CELL - t), Vec3::new(x0 + CELL + t, H, z0 + CELL + t));
            }
        }
    }
    // 13 lamps in cells spread over the maze (every fourth cell in scan order).
    for k in 0..13 {
        let c = (k * 49) / 13 + 1;
        let (i, j) = (c % N, c / N);
        ceiling_lamp(&mut mesh, (i as f32 + 0.5) * CELL, H - 0.01, (j as f32 + 0.5) * CELL, 0.4, lamp);
    }
    // Camera path: from cell (0,0) to the cell farthest along the maze tree.
    let mut far = (0, 0);
    let mut best = 0;
    for i in 0..N {
        for j in 0..N {
            let mut d = 0;
            let mut c = (i, j);
            while let Some(p) = parent[c.0][c.1] {
                d += 1;
                c = p;
            }
            if d > best {
                best = d;
                far = (i, j);
            }
        }
    }
    let mut path = vec![far];
    while let Some(p) = parent[path.last().unwrap().0][path.last().unwrap().1] {
        path.push(p);
    }
    path.reverse();
    let pts: Vec<Vec3> = path.iter().take(25).map(|&(i, j)| Vec3::new((i as f32 + 0.5) * CELL, 1.6, (j as f32 + 0.5) * CELL)).collect();
    let sequence = walk(&pts, 24.0, 1.5);
    Builtin::from_sequence("maze", mesh, materials, Vec::new(), sequence, 70.0)
}
