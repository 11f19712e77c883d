//! Nearest neighbours on the device: twin of `vpl_density::KnnDensity`'s
//! k-th-neighbour radii and nearest members, over a uniform grid built on
//! the device (the points' bounds by a reduction, then a counting sort: cell
//! counts, an exclusive prefix sum, a scatter), the structure the rest of
//! SMC's iteration needs on the device (its densities of eqs. 7 and 8, its
//! hits' nearest neighbours of line 6). Nothing about the grid crosses to
//! the host, so a kernel's own buffers (points some of which are absent)
//! can be searched where they lie ([`NeighbourSearch`]).

use crate::context::{GpuContext, GpuError};
use crate::device::Gpu;
use crate::kernel::{Binding, dispatch, finish_read, groups_1d, layout, pipeline, storage, storage_init, uniform};
use vpl_core::glam::{Vec3, Vec4};

/// Most neighbours a query may ask for.
pub const MAX_K: usize = 64;

/// Values a workgroup of the prefix sum scans; the grid has at most
/// `BLOCK²` cells.
const BLOCK: u64 = 1024;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    points: u32,
    queries: u32,
    k: u32,
    members: u32,
    row: u32,
    max_cells: u32,
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
    bounds: wgpu::ComputePipeline,
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
        let layout = layout(ctx, "neighbours", &[Binding::Uniform, r, r, w, w, w, w, w, w, w]);
        let src = include_str!("neighbours.wgsl");
        let p = |entry: &str| pipeline(ctx, entry, src, entry, &[&layout]);
        Kernels {
            bounds: p("bounds"),
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

/// A buffer range a search reads: rows of `vec4` (xyz a point, w 0 where
/// none is).
#[derive(Clone, Copy)]
pub(crate) struct Rows<'a> {
    pub buffer: &'a wgpu::Buffer,
    /// First row (its byte offset must meet the adapter's storage-offset alignment).
    pub first: u64,
    pub count: u64,
}

impl<'a> Rows<'a> {
    pub(crate) fn whole(buffer: &'a wgpu::Buffer, count: u64) -> Rows<'a> {
        Rows { buffer, first: 0, count }
    }

    fn binding(&self) -> wgpu::BindingResource<'a> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: self.buffer,
            offset: self.first * 16,
            size: wgpu::BufferSize::new(self.count.max(1) * 16),
        })
    }
}

/// The grid's working buffers for up to `points` points, reusable from
/// search to search (the scatter leaves the cell counts at zero).
pub(crate) struct NeighbourSearch {
    points: u64,
    max_cells: u64,
    cell_of: wgpu::Buffer,
    counts: wgpu::Buffer,
    start: wgpu::Buffer,
    sorted: wgpu::Buffer,
    sums: wgpu::Buffer,
    grid: wgpu::Buffer,
}

/// A search bound to its buffers, to record into an encoder.
pub(crate) struct BoundSearch {
    /// One bind group a dispatch shape (points, cells, queries): the
    /// parameters differ in `row` alone.
    groups: [wgpu::BindGroup; 3],
    shapes: [(u32, u32, u32); 3],
    /// Blocks of cells the scan covers: this search's grid, not the buffers'.
    blocks: u32,
}

/// About 8 cells a point, in whole scan blocks, at most `BLOCK²`.
fn cells_for(points: u64) -> u64 {
    (8 * points.max(8)).next_multiple_of(BLOCK).min(BLOCK * BLOCK)
}

impl NeighbourSearch {
    /// Buffers for grids over at most `points` points: about 8 cells a
    /// point, at most `BLOCK²`.
    pub(crate) fn new(ctx: &GpuContext, points: u64) -> Result<NeighbourSearch, GpuError> {
        let max_cells = cells_for(points);
        Ok(NeighbourSearch {
            points,
            max_cells,
            cell_of: storage(ctx, "cell of", points * 4)?,
            counts: storage(ctx, "cell counts", max_cells * 4)?,
            start: storage(ctx, "cell starts", max_cells * 4)?,
            sorted: storage(ctx, "sorted points", points * 4)?,
            sums: storage(ctx, "block sums", BLOCK * 4)?,
            grid: storage(ctx, "grid", 64)?,
        })
    }

    /// A search of `points` (at most the buffers' points) for the `k`
    /// nearest of each of `queries` (each point itself, not its own
    /// neighbour, when `None`), answers into `answers` (16 B a query).
    pub(crate) fn bind(
        &self,
        ctx: &GpuContext,
        kernels: &Kernels,
        points: Rows,
        queries: Option<Rows>,
        k: u32,
        answers: Rows,
    ) -> BoundSearch {
        debug_assert!(points.count <= self.points);
        let n_queries = queries.map_or(points.count, |q| q.count);
        // A grid sized for these points, within the buffers'.
        let max_cells = cells_for(points.count).min(self.max_cells);
        let shapes = [groups_1d(ctx, points.count, 64), groups_1d(ctx, max_cells, 256), groups_1d(ctx, n_queries, 64)];
        let rows = [shapes[0].0 * 64, shapes[1].0 * 256, shapes[2].0 * 64];
        let group = |row: u32| {
            let params = Params {
                points: points.count as u32,
                queries: n_queries as u32,
                k,
                members: queries.is_none() as u32,
                row,
                max_cells: max_cells as u32,
                pad: [0; 2],
            };
            let p = uniform(ctx, "grid params", &params);
            let resources = [
                p.as_entire_binding(),
                points.binding(),
                queries.map_or_else(|| points.binding(), |q| q.binding()),
                self.cell_of.as_entire_binding(),
                self.counts.as_entire_binding(),
                self.start.as_entire_binding(),
                self.sorted.as_entire_binding(),
                self.sums.as_entire_binding(),
                answers.binding(),
                self.grid.as_entire_binding(),
            ];
            let entries: Vec<wgpu::BindGroupEntry> =
                resources.into_iter().enumerate().map(|(i, resource)| wgpu::BindGroupEntry { binding: i as u32, resource }).collect();
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("neighbours"),
                layout: &kernels.layout,
                entries: &entries,
            })
        };
        BoundSearch { groups: [group(rows[0]), group(rows[1]), group(rows[2])], shapes, blocks: (max_cells / BLOCK) as u32 }
    }

    /// Records the grid's build and the queries: seven dispatches.
    pub(crate) fn record(&self, enc: &mut wgpu::CommandEncoder, kernels: &Kernels, s: &BoundSearch) {
        let [g_points, g_cells, g_queries] = &s.groups;
        let [points, cells, queries] = s.shapes;
        dispatch(enc, &kernels.bounds, &[g_points], (1, 1, 1));
        dispatch(enc, &kernels.count, &[g_points], points);
        dispatch(enc, &kernels.scan_blocks, &[g_cells], (s.blocks, 1, 1));
        dispatch(enc, &kernels.scan_sums, &[g_cells], (1, 1, 1));
        dispatch(enc, &kernels.scan_add, &[g_cells], cells);
        dispatch(enc, &kernels.scatter, &[g_points], points);
        dispatch(enc, &kernels.knn, &[g_queries], queries);
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
        let kernels = self.neighbour_kernels();
        let rows = |p: &[Vec3]| -> Vec<Vec4> { p.iter().map(|p| p.extend(1.0)).collect() };
        let b_points = storage_init(ctx, "neighbour points", &rows(points));
        let b_queries = queries.map(|q| storage_init(ctx, "neighbour queries", &rows(q)));
        let b_answers = storage(ctx, "neighbours", n_queries as u64 * 16)?;
        let search = NeighbourSearch::new(ctx, points.len() as u64)?;
        let bound = search.bind(
            ctx,
            kernels,
            Rows::whole(&b_points, points.len() as u64),
            b_queries.as_ref().map(|b| Rows::whole(b, n_queries as u64)),
            k as u32,
            Rows::whole(&b_answers, n_queries as u64),
        );
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        search.record(&mut enc, kernels, &bound);
        let answers: Vec<[u32; 4]> = finish_read(ctx, enc, &b_answers, n_queries)?;
        // Every query finds min(k, the points there are) neighbours; fewer
        // means the device stopped searching early.
        let available = if queries.is_none() { points.len() - 1 } else { points.len() };
        if answers.iter().any(|a| (a[3] as usize) < k.min(available)) {
            return Err(GpuError::CutShort("a nearest-neighbour search"));
        }
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
