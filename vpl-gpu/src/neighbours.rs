//! Nearest neighbours on the device: twin of `vpl_density::KnnDensity`'s
//! k-th-neighbour radii and nearest members, over a uniform grid built on
//! the device by a counting sort (cell counts, an exclusive prefix sum, a
//! scatter), the structure the rest of SMC's iteration needs on the device
//! (its densities of eqs. 7 and 8, its hits' nearest neighbours of line 6).

use crate::context::{GpuContext, GpuError};
use crate::device::Gpu;
use crate::kernel::{Binding, bind, dispatch, finish_read, groups_1d, layout, pipeline, storage, storage_init, uniform};
use vpl_core::glam::{Vec3, Vec4};

/// Most neighbours a query may ask for.
pub const MAX_K: usize = 64;

/// Values a workgroup of the prefix sum scans; the grid has at most
/// `BLOCK²` cells.
const BLOCK: u64 = 1024;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    lo: [f32; 4],
    dims: [u32; 4],
    points: u32,
    queries: u32,
    k: u32,
    members: u32,
    row: u32,
    blocks: u32,
    pad: [u32; 2],
}

/// What a query found: the squared distance to its k-th nearest point
/// (infinite when the set has fewer), and its nearest point with its
/// squared distance (ties to the lower index).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbours {
    /// Squared distance to the k-th nearest point.
    pub kth_sq: f32,
    /// The nearest point and its squared distance.
    pub nearest: Option<(usize, f32)>,
}

pub(crate) struct Kernels {
    layout: wgpu::BindGroupLayout,
    count: wgpu::ComputePipeline,
    scan_blocks: wgpu::ComputePipeline,
    scan_sums: wgpu::ComputePipeline,
    scan_add: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    knn: wgpu::ComputePipeline,
}

impl Kernels {
    pub(crate) fn new(ctx: &GpuContext) -> Kernels {
        let (r, w) = (Binding::Read, Binding::ReadWrite);
        let layout = layout(ctx, "neighbours", &[Binding::Uniform, r, r, w, w, w, w, w, w]);
        let src = include_str!("neighbours.wgsl");
        let p = |entry: &str| pipeline(ctx, entry, src, entry, &[&layout]);
        Kernels {
            count: p("count"),
            scan_blocks: p("scan_blocks"),
            scan_sums: p("scan_sums"),
            scan_add: p("scan_add"),
            scatter: p("scatter"),
            knn: p("knn"),
            layout,
        }
    }
}

/// The grid over `points`: its low corner, cell size and cells a side. The
/// cells are about 2 a point along the longest side's cube root, so a ring
/// or two around a query holds its few nearest points, and at most
/// `BLOCK²` in all.
fn grid(points: &[Vec3]) -> (Vec3, f32, [u32; 3]) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let extent = (hi - lo).max(Vec3::splat(1e-6));
    let per_side = (2.0 * (points.len() as f32).cbrt()).ceil().max(1.0);
    let mut h = extent.max_element() / per_side;
    loop {
        let d = (extent / h).floor() + 1.0;
        if (d.x * d.y * d.z) as u64 <= BLOCK * BLOCK {
            return (lo, h, [d.x as u32, d.y as u32, d.z as u32]);
        }
        h *= 1.25;
    }
}

impl Gpu {
    /// For each query (each point of `points` when `queries` is `None`,
    /// then not its own neighbour) its `k` nearest points of `points`, as
    /// [`Neighbours`]: the k-th squared distance equals
    /// `vpl_density::KnnDensity::radius_sq` (and, for the points
    /// themselves, `member_radii_sq`) and the nearest point
    /// `member_nearest` (bit for bit on lavapipe; a device that fuses a
    /// multiply-add may round once less). One
    /// submission: the points (and queries) go up as 16 B each, and 16 B a
    /// query come back.
    pub fn neighbours(&self, points: &[Vec3], queries: Option<&[Vec3]>, k: usize) -> Result<Vec<Neighbours>, GpuError> {
        if !(1..=MAX_K).contains(&k) {
            return Err(GpuError::Invalid(format!("{k} neighbours asked; the device finds 1 to {MAX_K}")));
        }
        if let Some(i) = points.iter().chain(queries.unwrap_or(&[])).position(|p| !p.is_finite()) {
            return Err(GpuError::Invalid(format!("point {i} has a non-finite coordinate")));
        }
        let n_queries = queries.map_or(points.len(), <[Vec3]>::len);
        if points.is_empty() || n_queries == 0 {
            return Ok(vec![Neighbours { kth_sq: f32::INFINITY, nearest: None }; n_queries]);
        }
        let ctx = self.ctx();
        let k_ = self.neighbour_kernels();
        let (lo, h, dims) = grid(points);
        let cells = dims[0] as u64 * dims[1] as u64 * dims[2] as u64;
        let blocks = cells.div_ceil(BLOCK);
        let point_groups = groups_1d(ctx, points.len() as u64, 64);
        let query_groups = groups_1d(ctx, n_queries as u64, 64);
        let cell_groups = groups_1d(ctx, cells, 256);
        let params = |row: u32| Params {
            lo: [lo.x, lo.y, lo.z, h],
            dims: [dims[0], dims[1], dims[2], cells as u32],
            points: points.len() as u32,
            queries: n_queries as u32,
            k: k as u32,
            members: queries.is_none() as u32,
            row,
            blocks: blocks as u32,
            pad: [0; 2],
        };
        let rows: Vec<Vec4> = points.iter().map(|p| p.extend(0.0)).collect();
        let b_points = storage_init(ctx, "neighbour points", &rows);
        let b_queries = match queries {
            Some(q) => storage_init(ctx, "neighbour queries", &q.iter().map(|p| p.extend(0.0)).collect::<Vec<Vec4>>()),
            None => storage(ctx, "no queries", 16)?,
        };
        let b_cell_of = storage(ctx, "cell of", points.len() as u64 * 4)?;
        let b_counts = storage(ctx, "cell counts", cells * 4)?;
        let b_start = storage(ctx, "cell starts", cells * 4)?;
        let b_sorted = storage(ctx, "sorted points", points.len() as u64 * 4)?;
        let b_sums = storage(ctx, "block sums", BLOCK * 4)?;
        let b_answers = storage(ctx, "neighbours", n_queries as u64 * 16)?;
        // One bind group a dispatch shape: the parameters differ in `row` alone.
        let group = |label: &str, row: u32| {
            let p = uniform(ctx, "grid params", &params(row));
            bind(ctx, label, &k_.layout, &[&p, &b_points, &b_queries, &b_cell_of, &b_counts, &b_start, &b_sorted, &b_sums, &b_answers])
        };
        let g_points = group("grid points", point_groups.0 * 64);
        let g_cells = group("grid cells", cell_groups.0 * 256);
        let g_queries = group("grid queries", query_groups.0 * 64);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &k_.count, &[&g_points], point_groups);
        dispatch(&mut enc, &k_.scan_blocks, &[&g_cells], (blocks as u32, 1, 1));
        dispatch(&mut enc, &k_.scan_sums, &[&g_cells], (1, 1, 1));
        dispatch(&mut enc, &k_.scan_add, &[&g_cells], cell_groups);
        dispatch(&mut enc, &k_.scatter, &[&g_points], point_groups);
        dispatch(&mut enc, &k_.knn, &[&g_queries], query_groups);
        let answers: Vec<[u32; 4]> = finish_read(ctx, enc, &b_answers, n_queries)?;
        Ok(answers
            .into_iter()
            .map(|a| Neighbours {
                // Fewer than k points found: no k-th neighbour.
                kth_sq: if (a[3] as usize) < k { f32::INFINITY } else { f32::from_bits(a[0]) },
                nearest: (a[1] != u32::MAX).then(|| (a[1] as usize, f32::from_bits(a[2]))),
            })
            .collect())
    }
}
