// Nearest neighbours on the device over a uniform grid built there: the
// valid points' bounds and the cell size (bounds), each point's cell
// (count), an exclusive prefix sum of the counts (scan_blocks, scan_sums,
// scan_add), the points' indices sorted by cell (scatter); then each query
// searches rings of cells around its own until no unsearched cell can hold
// a nearer point than its k-th (knn). A point or query whose w is 0 is
// absent, so fixed-size buffers a kernel fills in part need no compaction.

struct Params {
    // Rows of `points` and `queries` (present or not).
    points: u32,
    queries: u32,
    // Neighbours asked (the grid's k is this, at most the points there are).
    k: u32,
    // 1: the queries are the points, each not its own neighbour.
    members: u32,
    // `row` of 2D dispatches over points and over queries.
    row: u32,
    // Most cells the buffers hold (BLOCK · the scan's workgroups).
    max_cells: u32,
    pad0: u32,
    pad1: u32,
}

// What `bounds` finds.
struct Grid {
    // The grid's low corner (xyz) and cell size (w).
    lo: vec4<f32>,
    // Cells along x, y, z, and in all.
    dims: vec4<u32>,
    // Neighbours each query finds: min(k, points present, less itself).
    k: u32,
    // Points present.
    n: u32,
    // Blocks of BLOCK cells.
    blocks: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> queries: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> cell_of: array<u32>;
@group(0) @binding(4) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> start: array<u32>;
@group(0) @binding(6) var<storage, read_write> sorted: array<u32>;
@group(0) @binding(7) var<storage, read_write> block_sums: array<u32>;
// Per query: the k-th squared distance, the nearest point, its squared
// distance, the neighbours found.
@group(0) @binding(8) var<storage, read_write> answers: array<vec4<u32>>;
@group(0) @binding(9) var<storage, read_write> grid: Grid;

const NONE: u32 = 0xffffffffu;
const KMAX: u32 = 64u;
const BLOCK: u32 = 1024u;
const INF: f32 = 3.4028235e38;

fn present(p: vec4<f32>) -> bool {
    return p.w != 0.0;
}

var<workgroup> lo_tmp: array<vec3<f32>, 256>;
var<workgroup> hi_tmp: array<vec3<f32>, 256>;
var<workgroup> n_tmp: array<u32, 256>;

// One workgroup: the present points' bounds and count, and the grid over
// them: cells about 2 a point along the longest side's cube root, so a ring
// or two around a query holds its few nearest points, at most max_cells.
@compute @workgroup_size(256)
fn bounds(@builtin(local_invocation_index) li: u32) {
    var lo = vec3<f32>(INF);
    var hi = vec3<f32>(-INF);
    var n = 0u;
    for (var i = li; i < params.points; i = i + 256u) {
        let p = points[i];
        if (present(p)) {
            lo = min(lo, p.xyz);
            hi = max(hi, p.xyz);
            n = n + 1u;
        }
    }
    lo_tmp[li] = lo;
    hi_tmp[li] = hi;
    n_tmp[li] = n;
    workgroupBarrier();
    for (var off = 128u; off > 0u; off = off / 2u) {
        if (li < off) {
            lo_tmp[li] = min(lo_tmp[li], lo_tmp[li + off]);
            hi_tmp[li] = max(hi_tmp[li], hi_tmp[li + off]);
            n_tmp[li] = n_tmp[li] + n_tmp[li + off];
        }
        workgroupBarrier();
    }
    if (li != 0u) { return; }
    let count = n_tmp[0];
    var l = lo_tmp[0];
    var extent = max(hi_tmp[0] - l, vec3<f32>(1e-6));
    if (count == 0u) {
        l = vec3<f32>(0.0);
        extent = vec3<f32>(1.0);
    }
    let per_side = max(ceil(2.0 * pow(f32(max(count, 1u)), 1.0 / 3.0)), 1.0);
    var h = max(max(extent.x, extent.y), extent.z) / per_side;
    var d = floor(extent / h) + vec3<f32>(1.0);
    loop {
        if (d.x * d.y * d.z <= f32(params.max_cells)) { break; }
        h = h * 1.25;
        d = floor(extent / h) + vec3<f32>(1.0);
    }
    let dims = vec3<u32>(d);
    let cells = dims.x * dims.y * dims.z;
    var k = min(params.k, count);
    if (params.members != 0u) { k = min(params.k, max(count, 1u) - 1u); }
    grid = Grid(vec4<f32>(l, h), vec4<u32>(dims, cells), k, count, (cells + BLOCK - 1u) / BLOCK, 0u);
}

fn cell_coords(p: vec3<f32>) -> vec3<i32> {
    let g = (p - grid.lo.xyz) / grid.lo.w;
    let hi = vec3<i32>(grid.dims.xyz) - vec3<i32>(1);
    return clamp(vec3<i32>(floor(g)), vec3<i32>(0), hi);
}

fn cell_index(c: vec3<i32>) -> u32 {
    return (u32(c.z) * grid.dims.y + u32(c.y)) * grid.dims.x + u32(c.x);
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.points || !present(points[i])) { return; }
    let c = cell_index(cell_coords(points[i].xyz));
    cell_of[i] = c;
    atomicAdd(&counts[c], 1u);
}

var<workgroup> scan_tmp: array<u32, 1024>;

// Inclusive scan of scan_tmp's BLOCK values (Hillis–Steele), 4 a thread
// of the workgroup's 256; called in uniform control flow.
fn scan_in_place(li: u32) {
    var off = 1u;
    loop {
        if (off >= BLOCK) { break; }
        var add: array<u32, 4>;
        for (var j = 0u; j < 4u; j = j + 1u) {
            let e = li * 4u + j;
            add[j] = 0u;
            if (e >= off) { add[j] = scan_tmp[e - off]; }
        }
        workgroupBarrier();
        for (var j = 0u; j < 4u; j = j + 1u) {
            scan_tmp[li * 4u + j] = scan_tmp[li * 4u + j] + add[j];
        }
        workgroupBarrier();
        off = off * 2u;
    }
}

// Exclusive scan of BLOCK counts a workgroup (4 a thread), into `start`,
// and each block's total into `block_sums`.
@compute @workgroup_size(256)
fn scan_blocks(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let base = wg.x * BLOCK;
    let cells = grid.dims.w;
    if (base >= cells) { return; }
    for (var j = 0u; j < 4u; j = j + 1u) {
        let e = base + li * 4u + j;
        var v = 0u;
        if (e < cells) { v = atomicLoad(&counts[e]); }
        scan_tmp[li * 4u + j] = v;
    }
    workgroupBarrier();
    scan_in_place(li);
    for (var j = 0u; j < 4u; j = j + 1u) {
        let e = li * 4u + j;
        var before = 0u;
        if (e > 0u) { before = scan_tmp[e - 1u]; }
        if (base + e < cells) { start[base + e] = before; }
    }
    if (li == 0u) { block_sums[wg.x] = scan_tmp[BLOCK - 1u]; }
}

// Exclusive scan of the block totals in place (at most BLOCK of them).
@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_index) li: u32) {
    for (var j = 0u; j < 4u; j = j + 1u) {
        let e = li * 4u + j;
        var v = 0u;
        if (e < grid.blocks) { v = block_sums[e]; }
        scan_tmp[e] = v;
    }
    workgroupBarrier();
    scan_in_place(li);
    for (var j = 0u; j < 4u; j = j + 1u) {
        let e = li * 4u + j;
        var before = 0u;
        if (e > 0u) { before = scan_tmp[e - 1u]; }
        if (e < grid.blocks) { block_sums[e] = before; }
    }
}

@compute @workgroup_size(256)
fn scan_add(@builtin(global_invocation_id) id: vec3<u32>) {
    let e = id.x + id.y * params.row;
    if (e >= grid.dims.w) { return; }
    start[e] = start[e] + block_sums[e / BLOCK];
}

// Each point's index into its cell's range (in no particular order within
// the cell: the queries break ties by index).
@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.points || !present(points[i])) { return; }
    let c = cell_of[i];
    let slot = atomicSub(&counts[c], 1u) - 1u;
    sorted[start[c] + slot] = i;
}

fn d2(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let d = a - b;
    // The order of the host's sums: (x² + y²) + z².
    let xx = d.x * d.x;
    let yy = d.y * d.y;
    let zz = d.z * d.z;
    return (xx + yy) + zz;
}

@compute @workgroup_size(64)
fn knn(@builtin(global_invocation_id) id: vec3<u32>) {
    let qi = id.x + id.y * params.row;
    if (qi >= params.queries) { return; }
    var q4: vec4<f32>;
    if (params.members != 0u) { q4 = points[qi]; } else { q4 = queries[qi]; }
    if (!present(q4)) {
        answers[qi] = vec4<u32>(bitcast<u32>(INF), NONE, bitcast<u32>(INF), 0u);
        return;
    }
    let q = q4.xyz;
    let k = min(grid.k, KMAX);
    if (k == 0u) {
        answers[qi] = vec4<u32>(bitcast<u32>(INF), NONE, bitcast<u32>(INF), 0u);
        return;
    }
    var best_d: array<f32, 64>;
    var best_i: array<u32, 64>;
    var found = 0u;
    let c0 = cell_coords(q);
    let dims = vec3<i32>(grid.dims.xyz);
    let h = grid.lo.w;
    let lo = grid.lo.xyz;
    var r = 0;
    loop {
        // The cells at Chebyshev distance r from c0.
        for (var dz = -r; dz <= r; dz = dz + 1) {
            let z = c0.z + dz;
            if (z < 0 || z >= dims.z) { continue; }
            for (var dy = -r; dy <= r; dy = dy + 1) {
                let y = c0.y + dy;
                if (y < 0 || y >= dims.y) { continue; }
                var step = 1;
                if (abs(dy) < r && abs(dz) < r) { step = max(2 * r, 1); }
                for (var dx = -r; dx <= r; dx = dx + step) {
                    let x = c0.x + dx;
                    if (x < 0 || x >= dims.x) { continue; }
                    let c = cell_index(vec3<i32>(x, y, z));
                    var end = grid.n;
                    if (c + 1u < grid.dims.w) { end = start[c + 1u]; }
                    for (var s = start[c]; s < end; s = s + 1u) {
                        let j = sorted[s];
                        if (params.members != 0u && j == qi) { continue; }
                        let dj = d2(q, points[j].xyz);
                        // Insert (dj, j) into the k best, ordered by distance then index.
                        if (found == k) {
                            let wd = best_d[k - 1u];
                            if (dj > wd || (dj == wd && j > best_i[k - 1u])) { continue; }
                        } else {
                            found = found + 1u;
                        }
                        var m = found - 1u;
                        loop {
                            if (m == 0u) { break; }
                            let pd = best_d[m - 1u];
                            if (pd < dj || (pd == dj && best_i[m - 1u] < j)) { break; }
                            best_d[m] = pd;
                            best_i[m] = best_i[m - 1u];
                            m = m - 1u;
                        }
                        best_d[m] = dj;
                        best_i[m] = j;
                    }
                }
            }
        }
        // Nothing unsearched lies nearer than the searched block's faces
        // that are not the grid's own.
        var bound = INF;
        var whole = true;
        for (var a = 0; a < 3; a = a + 1) {
            if (c0[a] - r > 0) {
                whole = false;
                bound = min(bound, q[a] - (lo[a] + f32(c0[a] - r) * h));
            }
            if (c0[a] + r < dims[a] - 1) {
                whole = false;
                bound = min(bound, (lo[a] + f32(c0[a] + r + 1) * h) - q[a]);
            }
        }
        if (whole) { break; }
        if (found == k && bound > 0.0 && best_d[k - 1u] <= bound * bound) { break; }
        r = r + 1;
    }
    var out = vec4<u32>(bitcast<u32>(INF), NONE, bitcast<u32>(INF), found);
    if (found == k && k > 0u) { out.x = bitcast<u32>(best_d[k - 1u]); }
    if (found > 0u) {
        out.y = best_i[0];
        out.z = bitcast<u32>(best_d[0]);
    }
    answers[qi] = out;
}
