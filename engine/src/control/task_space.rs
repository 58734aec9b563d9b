//! The whole-body layer's task hierarchy in task space ([`super::wbc`]'s
//! pass 1, see [`super::wbc::WholeBody`]'s docs for the algebra).
//!
//! With the tasks' rows stacked into `J` (`R × nv`) and `G = J M⁻¹ Jᵀ`,
//! every quantity of the dense recursion is `M⁻¹ Jᵀ` times an `R`-vector or
//! matrix: `q̈ = M⁻¹ Jᵀ β`, `N_i = I − M⁻¹ Jᵀ C_i J`. The recursion on `β`
//! and `C` is the same algebra, damping included, in `R` dimensions.
//!
//! `G` comes from the tree's sparse factor `M = Lᵀ L` (Featherstone 2008,
//! §6.5, "LTL": `L` has the tree's sparsity, no fill-in): `G = Wᵀ W` with
//! `W = L⁻ᵀ Jᵀ`. `W` is kept by coordinates (row `i`: coordinate `i`'s
//! entries for every task row); a leg's coordinate has entries only in the
//! rows of tasks on that leg, so `G` is six full rank-one updates (the base)
//! and small ones (the legs).
//!
//! Task-space rows are padded to `N` (24 when `R ≤ 24`, as for any robot of
//! four legs of up to four joints; else 48) with zeros, so that every
//! product runs over whole rows of a length known when compiling.

use crate::linalg::{cholesky_dense, cholesky_dense_solve};
use crate::model::{Model, NO_PARENT};
use multiversion::multiversion;

/// Most rows of one task.
pub(crate) const MAX_ROWS: usize = 3 * super::force_qp::MAX_FEET;

/// Row lengths of the task-space matrices.
const SMALL: usize = 24;
const LARGE: usize = 48;

/// The velocity coordinates' tree (Featherstone's `λ(i)`: the coordinate
/// each one's motion is carried by; the free base's six form a chain), kept
/// as each coordinate's ancestors, nearest first, in one array: the sparse
/// factor's loops then read their indices instead of chasing parents.
#[derive(Clone, Debug)]
struct DofTree {
    /// Ancestors of coordinate `i`: `anc[start[i]..start[i + 1]]`, nearest first.
    anc: Vec<usize>,
    start: Vec<usize>,
    /// Descendants of coordinate `i`: `desc[dstart[i]..dstart[i + 1]]`, in
    /// increasing order.
    desc: Vec<usize>,
    dstart: Vec<usize>,
}

impl DofTree {
    fn of(model: &Model) -> DofTree {
        let mut parent = vec![usize::MAX; model.nv];
        for (i, p) in parent.iter_mut().enumerate() {
            let b = model.v_body[i];
            if i > model.idx_v[b] {
                *p = i - 1; // within a multi-DOF joint (the free base)
                continue;
            }
            let mut j = model.parent[b];
            while j != NO_PARENT {
                let n = model.joint_type[j].nv();
                if n > 0 {
                    *p = model.idx_v[j] + n - 1;
                    break;
                }
                j = model.parent[j];
            }
        }
        let mut anc = Vec::new();
        let mut start = vec![0];
        for i in 0..model.nv {
            let mut j = parent[i];
            while j != usize::MAX {
                anc.push(j);
                j = parent[j];
            }
            start.push(anc.len());
        }
        let mut desc = Vec::new();
        let mut dstart = vec![0];
        for i in 0..model.nv {
            for k in i + 1..model.nv {
                if anc[start[k]..start[k + 1]].contains(&i) {
                    desc.push(k);
                }
            }
            dstart.push(desc.len());
        }
        DofTree {
            anc,
            start,
            desc,
            dstart,
        }
    }

    /// Descendants of coordinate `i`, in increasing order.
    #[inline]
    fn descendants(&self, i: usize) -> &[usize] {
        &self.desc[self.dstart[i]..self.dstart[i + 1]]
    }

    /// Ancestors of coordinate `i`, nearest first.
    #[inline]
    fn ancestors(&self, i: usize) -> &[usize] {
        &self.anc[self.start[i]..self.start[i + 1]]
    }
}

/// The task-space workspace (allocated for `R ≤ 24` task rows; a solve with
/// more grows it once).
#[derive(Clone, Debug)]
pub(crate) struct TaskSpace {
    nv: usize,
    tree: DofTree,
    /// `L` of `M = Lᵀ L` (row-major; row `i` at `i`'s ancestors and `i`)
    /// and `1 / L_ii`.
    l: Vec<f64>,
    inv_diag: Vec<f64>,
    /// Row length of the task-space matrices below (24 or 48).
    width: usize,
    /// `W = L⁻ᵀ Jᵀ` (nv rows of `width`).
    wd: Vec<f64>,
    /// `G` and `C` (`width` rows of `width`), `β` (`width`).
    g: Vec<f64>,
    cm: Vec<f64>,
    beta: Vec<f64>,
    /// One task's `A`, `T = A G`, `Dᵀ = A (I − C G)ᵀ`, `X = Λ A`, and the
    /// last task's `E G C` (`MAX_ROWS` rows of `width`).
    am: Vec<f64>,
    tm: Vec<f64>,
    dm: Vec<f64>,
    xm: Vec<f64>,
    qm: Vec<f64>,
    /// `Λ⁻¹` of one task, factored, and its right-hand side.
    kk: [f64; MAX_ROWS * MAX_ROWS],
    y: [f64; MAX_ROWS],
    x: Vec<f64>,
}

impl TaskSpace {
    pub(crate) fn new(model: &Model) -> TaskSpace {
        let nv = model.nv;
        let mut t = TaskSpace {
            nv,
            tree: DofTree::of(model),
            l: vec![0.0; nv * nv],
            inv_diag: vec![0.0; nv],
            width: 0,
            wd: Vec::new(),
            g: Vec::new(),
            cm: Vec::new(),
            beta: Vec::new(),
            am: Vec::new(),
            tm: Vec::new(),
            dm: Vec::new(),
            xm: Vec::new(),
            qm: Vec::new(),
            kk: [0.0; MAX_ROWS * MAX_ROWS],
            y: [0.0; MAX_ROWS],
            x: vec![0.0; nv],
        };
        t.size(SMALL);
        t
    }

    fn size(&mut self, width: usize) {
        self.width = width;
        self.wd = vec![0.0; self.nv * width];
        self.g = vec![0.0; width * width];
        self.cm = vec![0.0; width * width];
        self.beta = vec![0.0; width];
        for b in [
            &mut self.am,
            &mut self.tm,
            &mut self.dm,
            &mut self.xm,
            &mut self.qm,
        ] {
            *b = vec![0.0; MAX_ROWS * width];
        }
    }

    /// Factors `M = Lᵀ L` (Featherstone 2008, Table 6.3, "LTL"); `false` when
    /// `m` is not positive definite.
    pub(crate) fn factor(&mut self, m: &[f64]) -> bool {
        let n = self.nv;
        let h = &mut self.l;
        h.copy_from_slice(m);
        let lk = &mut self.x;
        for k in (0..n).rev() {
            let d = h[k * n + k];
            if d <= 0.0 || !d.is_finite() {
                return false;
            }
            let d = d.sqrt();
            h[k * n + k] = d;
            let inv = 1.0 / d;
            self.inv_diag[k] = inv;
            // row k of L at k's ancestors, then the ancestors' rows less
            // its outer product (the ancestors of ancestor anc[p] are anc[p..])
            let anc = self.tree.ancestors(k);
            let na = anc.len();
            let rowk = &mut h[k * n..(k + 1) * n];
            for (l, &i) in lk[..na].iter_mut().zip(anc) {
                *l = rowk[i] * inv;
                rowk[i] = *l;
            }
            for p in 0..na {
                let i = anc[p];
                let lki = lk[p];
                let rowi = &mut h[i * n..(i + 1) * n];
                for (&j, &lkj) in anc[p..].iter().zip(&lk[p..na]) {
                    rowi[j] -= lki * lkj;
                }
            }
        }
        true
    }

    /// The hierarchy's accelerations into `qdd`, after [`TaskSpace::factor`]:
    /// `rows` is `J` (`R × nv`, row-major), `target` the tasks' targets (bias
    /// subtracted), `tasks` each task's first row and row count in order of
    /// priority (contiguous, `R` in all), `damping` the `λ` of `Λ⁻¹ = J N
    /// M⁻¹ (J N)ᵀ + λ I`.
    pub(crate) fn solve(
        &mut self,
        rows: &[f64],
        target: &[f64],
        tasks: &[(usize, usize); 4],
        damping: f64,
        qdd: &mut [f64],
    ) {
        let rt = tasks.iter().map(|&(o, r)| o + r).max().unwrap_or(0);
        if rt <= SMALL {
            solve_small(self, rows, target, tasks, damping, qdd);
        } else {
            if self.width < LARGE {
                self.size(LARGE);
            }
            solve_large(self, rows, target, tasks, damping, qdd);
        }
    }
}

#[multiversion(targets("x86_64+avx2+fma"))]
fn solve_small(
    t: &mut TaskSpace,
    rows: &[f64],
    target: &[f64],
    tasks: &[(usize, usize); 4],
    damping: f64,
    qdd: &mut [f64],
) {
    solve_n::<SMALL>(t, rows, target, tasks, damping, qdd);
}

#[multiversion(targets("x86_64+avx2+fma"))]
fn solve_large(
    t: &mut TaskSpace,
    rows: &[f64],
    target: &[f64],
    tasks: &[(usize, usize); 4],
    damping: f64,
    qdd: &mut [f64],
) {
    solve_n::<LARGE>(t, rows, target, tasks, damping, qdd);
}

/// Row `i` of a matrix of rows of `N`.
#[inline(always)]
fn row<const N: usize>(m: &[f64], i: usize) -> &[f64; N] {
    m[i * N..(i + 1) * N].try_into().expect("row")
}

#[inline(always)]
fn row_mut<const N: usize>(m: &mut [f64], i: usize) -> &mut [f64; N] {
    (&mut m[i * N..(i + 1) * N]).try_into().expect("row")
}

/// `y ← y + a x`.
#[inline(always)]
fn axpy<const N: usize>(y: &mut [f64; N], a: f64, x: &[f64; N]) {
    for k in 0..N {
        y[k] += a * x[k];
    }
}

/// `a · b` in four interleaved partial sums (`N` a multiple of 4).
#[inline(always)]
fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut acc = [0.0; 4];
    for k in (0..N).step_by(4) {
        for j in 0..4 {
            acc[j] += a[k + j] * b[k + j];
        }
    }
    (acc[0] + acc[2]) + (acc[1] + acc[3])
}

/// `out += Σ_k coef[k] · row k of rows`.
#[inline(always)]
fn add_rows<const N: usize>(out: &mut [f64; N], coef: &[f64], rows: &[f64]) {
    add_rows_by(out, coef, |k| row::<N>(rows, k));
}

/// `out += Σ_k coef[k] · row(k)`, four rows at a time (one pass over `out`
/// per four rows, then one for the last one to three).
#[inline(always)]
fn add_rows_by<'a, const N: usize>(
    out: &mut [f64; N],
    coef: &[f64],
    row: impl Fn(usize) -> &'a [f64; N],
) {
    let mut quads = coef.chunks_exact(4);
    let mut k = 0;
    for c in quads.by_ref() {
        let (r0, r1, r2, r3) = (row(k), row(k + 1), row(k + 2), row(k + 3));
        for j in 0..N {
            out[j] += (c[0] * r0[j] + c[1] * r1[j]) + (c[2] * r2[j] + c[3] * r3[j]);
        }
        k += 4;
    }
    match *quads.remainder() {
        [c0, c1, c2] => {
            let (r0, r1, r2) = (row(k), row(k + 1), row(k + 2));
            for j in 0..N {
                out[j] += (c0 * r0[j] + c1 * r1[j]) + c2 * r2[j];
            }
        }
        [c0, c1] => {
            let (r0, r1) = (row(k), row(k + 1));
            for j in 0..N {
                out[j] += c0 * r0[j] + c1 * r1[j];
            }
        }
        [c0] => axpy(out, c0, row(k)),
        _ => {}
    }
}

#[inline(always)]
fn solve_n<const N: usize>(
    t: &mut TaskSpace,
    rows: &[f64],
    target: &[f64],
    tasks: &[(usize, usize); 4],
    damping: f64,
    qdd: &mut [f64],
) {
    let nv = t.nv;
    let rt = tasks.iter().map(|&(o, r)| o + r).max().unwrap_or(0);
    let wd = &mut t.wd[..nv * N];
    let mut coef = [0.0; LARGE];
    let mut idx = [0usize; LARGE];
    // W = L⁻ᵀ Jᵀ by coordinates, leaves to root, all task rows at once:
    // W_i = (Jᵀ_i − Σ_{k below i} L_ki W_k) / L_ii
    for i in (0..nv).rev() {
        let (head, tail) = wd.split_at_mut((i + 1) * N);
        let wi = row_mut::<N>(head, i);
        wi.fill(0.0);
        for (a, x) in wi[..rt].iter_mut().enumerate() {
            *x = rows[a * nv + i];
        }
        let desc = t.tree.descendants(i);
        for (c, &k) in coef.iter_mut().zip(desc) {
            *c = -t.l[k * nv + i];
        }
        add_rows_by(wi, &coef[..desc.len()], |p| row::<N>(tail, desc[p] - i - 1));
        let d = t.inv_diag[i];
        wi.iter_mut().for_each(|x| *x *= d);
    }
    // G = W Wᵀ: row a sums the coordinates' rows that task row a moves
    let g = &mut t.g[..N * N];
    for a in 0..N {
        let ga = row_mut::<N>(g, a);
        ga.fill(0.0);
        if a >= rt {
            continue;
        }
        let mut m = 0;
        for i in 0..nv {
            let c = wd[i * N + a];
            if c != 0.0 {
                coef[m] = c;
                idx[m] = i;
                m += 1;
            }
        }
        add_rows_by(ga, &coef[..m], |p| row::<N>(wd, idx[p]));
    }
    // the tasks with rows, in order; the one before the last computes what
    // the last needs of C instead of C itself
    let mut order = [(0usize, 0usize); 4];
    let mut n = 0;
    for &(o, r) in tasks {
        if r > 0 {
            order[n] = (o, r);
            n += 1;
        }
    }
    t.cm[..N * N].fill(0.0);
    t.beta[..N].fill(0.0);
    for k in 0..n {
        let (o, r) = order[k];
        task::<N>(
            t,
            &target[o..o + r],
            TaskShape {
                o,
                r,
                last: k + 1 == n,
                a_from_q: k + 1 == n && k > 0,
                next_last: (k + 2 == n).then(|| order[k + 1]),
            },
            damping,
        );
    }
    // q̈ = M⁻¹ Jᵀ β = L⁻¹ (W β)
    let beta = row::<N>(&t.beta, 0);
    for (i, x) in t.x.iter_mut().enumerate() {
        *x = dot(row::<N>(&t.wd, i), beta);
    }
    for i in 0..nv {
        let li = &t.l[i * nv..(i + 1) * nv];
        let mut s = t.x[i];
        for &j in t.tree.ancestors(i) {
            s -= li[j] * t.x[j];
        }
        t.x[i] = s * t.inv_diag[i];
    }
    qdd.copy_from_slice(&t.x);
}

/// Where a task sits in the hierarchy ([`task`]).
#[derive(Clone, Copy)]
struct TaskShape {
    /// The task's first row and its row count.
    o: usize,
    r: usize,
    /// The last task: no `C` to update.
    last: bool,
    /// `E_i G C_{i−1}` is in `qm` (the task before computed it).
    a_from_q: bool,
    /// The next task's rows when it is the last: compute its `E G C_i`
    /// into `qm` instead of `C_i`.
    next_last: Option<(usize, usize)>,
}

/// Task `i` of the hierarchy: `G` in `t.g`, `C_{i−1}` in `t.cm` (zero past
/// row and column `o`), updated to `C_i` unless the task is the last or
/// the one before it; `β` gains `A_iᵀ Λ_i e_i`. A task whose `Λ_i⁻¹` does
/// not factor is skipped, as the dense recursion skips it.
///
/// Rows of `A`, `T`, `Dᵀ` and `X` are zero past `s = o + r`, and rows of
/// `C` past `o`, so whole-row products give the leading blocks' products.
#[inline(always)]
fn task<const N: usize>(t: &mut TaskSpace, target: &[f64], shape: TaskShape, damping: f64) {
    let TaskShape { o, r, .. } = shape;
    let s = o + r;
    let g = &t.g[..N * N];
    let cm = &mut t.cm[..N * N];
    let (am, tm, dm, xm, qm) = (
        &mut t.am[..MAX_ROWS * N],
        &mut t.tm[..MAX_ROWS * N],
        &mut t.dm[..MAX_ROWS * N],
        &mut t.xm[..MAX_ROWS * N],
        &mut t.qm[..MAX_ROWS * N],
    );
    let kk = &mut t.kk[..r * r];
    let y = &mut t.y[..r];
    let mut coef = [0.0; LARGE];
    // A = E_i (I − G C): [−G_io C_oo, I, 0]
    for a in 0..r {
        let arow = row_mut::<N>(am, a);
        if shape.a_from_q {
            let q = row::<N>(qm, a);
            for j in 0..N {
                arow[j] = -q[j];
            }
        } else {
            arow.fill(0.0);
            let grow = row::<N>(g, o + a);
            for (k, gk) in coef[..o].iter_mut().zip(grow) {
                *k = -gk;
            }
            add_rows(arow, &coef[..o], cm);
        }
        arow[o + a] = 1.0;
    }
    // T = A G: row a is G's row o + a plus A's first o entries times G's rows
    for a in 0..r {
        let trow = row_mut::<N>(tm, a);
        trow.copy_from_slice(row::<N>(g, o + a));
        add_rows(trow, &row::<N>(am, a)[..o], g);
    }
    // Λ⁻¹ = T Aᵀ + λ I (lower triangle), factored
    for a in 0..r {
        for b in 0..=a {
            let v = dot(row::<N>(tm, a), row::<N>(am, b));
            kk[a * r + b] = v + if a == b { damping } else { 0.0 };
        }
    }
    if !cholesky_dense(kk, r) {
        // the task has no room left in the null space: C stays, and the
        // last task's E G C is that of C
        if let Some((ol, rl)) = shape.next_last {
            for a in 0..rl {
                let qrow = row_mut::<N>(qm, a);
                qrow.fill(0.0);
                add_rows(qrow, &row::<N>(g, ol + a)[..o], cm);
            }
        }
        return;
    }
    // e = x − E_i G β (β is zero past o); β += Aᵀ Λ e
    let beta = row_mut::<N>(&mut t.beta, 0);
    for a in 0..r {
        y[a] = target[a] - dot(row::<N>(g, o + a), beta);
    }
    cholesky_dense_solve(kk, r, y);
    add_rows(beta, y, am);
    if shape.last {
        return;
    }
    // Dᵀ = A − T Cᵀ (C is zero past o)
    for a in 0..r {
        let trow = row::<N>(tm, a);
        for c in 0..o {
            coef[c] = dot(row::<N>(cm, c), trow);
        }
        let (arow, drow) = (row::<N>(am, a), row_mut::<N>(dm, a));
        drow.copy_from_slice(arow);
        for c in 0..o {
            drow[c] -= coef[c];
        }
    }
    // X = Λ A: the factor's two triangular solves, a whole row at a time
    for a in 0..r {
        let (done, rest) = xm.split_at_mut(a * N);
        let xrow = row_mut::<N>(rest, 0);
        xrow.copy_from_slice(row::<N>(am, a));
        for (k, l) in coef[..a].iter_mut().zip(&kk[a * r..a * r + a]) {
            *k = -l;
        }
        add_rows(xrow, &coef[..a], done);
        let inv = 1.0 / kk[a * r + a];
        xrow.iter_mut().for_each(|x| *x *= inv);
    }
    for a in (0..r).rev() {
        let (head, tail) = xm.split_at_mut((a + 1) * N);
        let xrow = row_mut::<N>(head, a);
        for b in a + 1..r {
            coef[b - a - 1] = -kk[b * r + a];
        }
        add_rows(xrow, &coef[..r - a - 1], tail);
        let inv = 1.0 / kk[a * r + a];
        xrow.iter_mut().for_each(|x| *x *= inv);
    }
    if let Some((ol, rl)) = shape.next_last {
        // the last task's E G C_i = E G C_{i−1} + (E G D) X (its rows
        // start at s: only the first s columns of E G C_i are read)
        debug_assert_eq!(ol, s);
        for a in 0..rl {
            let gl = row::<N>(g, ol + a);
            let qrow = row_mut::<N>(qm, a);
            qrow.fill(0.0);
            add_rows(qrow, &gl[..o], cm);
            for (b, k) in coef[..r].iter_mut().enumerate() {
                *k = dot(gl, row::<N>(dm, b));
            }
            add_rows(qrow, &coef[..r], xm);
            qrow[s..].fill(0.0);
        }
        return;
    }
    // C += D X (rows 0..s)
    for c in 0..s {
        for (a, k) in coef[..r].iter_mut().enumerate() {
            *k = dm[a * N + c];
        }
        add_rows(row_mut::<N>(cm, c), &coef[..r], xm);
    }
}
