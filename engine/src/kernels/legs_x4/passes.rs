//! The lane passes of [`super`]: forward kinematics, ABA and RNEA with one
//! AVX lane per leg. Each statement mirrors the general path's (named in
//! comments).

use super::workspace::{GroupAba, GroupKinematics, give_back_group_aba, take_group_aba};
use crate::data::Data;
use crate::kernels::f64x4::{F4, Force4, Inertia4, M3, Motion4, Sym6x4, Transform4, V3, outer};
use crate::model::{JointType, Model};
use crate::plan::{GroupStep, LEGS, LegLanes};
use crate::spatial::{Force, Motion, RigidInertia, Sym6, Transform};
use glam::DVec3;

/// The motions `m[i]` of the bodies `grp` in lanes, element by element (no
/// copies of whole structs).
#[inline(always)]
fn gather_motions(m: &[Motion], grp: &[usize; LEGS]) -> Motion4 {
    let [a, b, c, d] = *grp;
    let (ma, mb, mc, md) = (&m[a], &m[b], &m[c], &m[d]);
    Motion4::new(
        gather_v3([&ma.lin, &mb.lin, &mc.lin, &md.lin]),
        gather_v3([&ma.ang, &mb.ang, &mc.ang, &md.ang]),
    )
}

/// The lane cache's velocities again from `data.vel`, after forward
/// kinematics updated only the velocities (the same `q`, another `v`): the
/// subspaces and inertias in the cache still hold.
pub(crate) fn refresh_lane_velocities(plan: &LegLanes, data: &mut Data) {
    for (gk, grp) in data.lanes.groups.iter_mut().zip(&plan.groups) {
        gk.v = gather_motions(&data.vel, grp);
    }
}

/// Four vectors in lanes, element by element.
#[inline(always)]
fn gather_v3(p: [&DVec3; LEGS]) -> V3 {
    V3::new(
        F4::from_array([p[0].x, p[1].x, p[2].x, p[3].x]),
        F4::from_array([p[0].y, p[1].y, p[2].y, p[3].y]),
        F4::from_array([p[0].z, p[1].z, p[2].z, p[3].z]),
    )
}

/// Group `grp`'s motion subspaces and inertias (reference frame) in lanes,
/// gathered from the per-body arrays that forward kinematics filled (when
/// `data`'s lane cache does not hold them).
#[inline(always)]
fn gather_kinematics(grp: &[usize; LEGS], data: &Data) -> GroupKinematics {
    let [a, b, c, d] = *grp;
    let v3 = gather_v3;
    let ir = &data.inertia_ref;
    let (ia, ib, ic, id) = (&ir[a], &ir[b], &ir[c], &ir[d]);
    let (ja, jb, jc, jd) = (
        &ia.inertia_com,
        &ib.inertia_com,
        &ic.inertia_com,
        &id.inertia_com,
    );
    let inertia = Inertia4 {
        mass: F4::from_array([ia.mass, ib.mass, ic.mass, id.mass]),
        com: v3([&ia.com, &ib.com, &ic.com, &id.com]),
        inertia_com: M3::from_cols(
            v3([&ja.x_axis, &jb.x_axis, &jc.x_axis, &jd.x_axis]),
            v3([&ja.y_axis, &jb.y_axis, &jc.y_axis, &jd.y_axis]),
            v3([&ja.z_axis, &jb.z_axis, &jc.z_axis, &jd.z_axis]),
        ),
    };
    GroupKinematics {
        s: gather_motions(&data.s, grp),
        inertia,
        v: gather_motions(&data.vel, grp),
    }
}

/// Group `g`'s (bodies `grp`) motion subspaces, inertias and velocities
/// (reference frame) in lanes: from `data`'s lane cache when it holds them,
/// else gathered from the per-body arrays that forward kinematics filled.
#[inline(always)]
pub(super) fn group_kinematics(
    g: usize,
    grp: &[usize; LEGS],
    data: &Data,
) -> (Motion4, Inertia4, Motion4) {
    let GroupKinematics { s, inertia, v } = if data.lanes.valid {
        data.lanes.groups[g]
    } else {
        gather_kinematics(grp, data)
    };
    (s, inertia, v)
}

/// Panics unless the four joint indices are below `nv`: one branch instead
/// of a bounds check per gather or store at those indices.
#[inline(always)]
fn assert_joints_within(idx: &[usize; LEGS], nv: usize) {
    let [j0, j1, j2, j3] = *idx;
    assert!(
        (j0 < nv) & (j1 < nv) & (j2 < nv) & (j3 < nv),
        "leg joints within nv"
    );
}

#[inline(always)]
pub(super) fn gather(x: &[f64], idx: &[usize; LEGS]) -> F4 {
    F4::from_array([x[idx[0]], x[idx[1]], x[idx[2]], x[idx[3]]])
}

/// `rot · R_k(angle)` as the scalar kinematics' fast path computes it: only
/// the two columns across axis `k` change. A macro, not a function: as an
/// `#[inline]` AVX function (Rust refuses `#[inline(always)]` with
/// `#[target_feature]`) LLVM inlined it into the pose loops or not
/// depending on unrelated code elsewhere in the crate, and out of line it
/// cost forward kinematics about 110 and `leg_end_points` about 47
/// instructions a step.
macro_rules! rotate_about_axis {
    ($rot:expr, $k:expr, $angle:expr) => {{
        let (rot, k, angle): (M3, usize, F4) = ($rot, $k, $angle);
        // `trig::kinematics_sin_cos` per lane
        let (s, c) = if crate::trig::DYNAMICS_USE_LIBM {
            angle.sin_cos()
        } else {
            let (s, c) = crate::trig::kinematics_sin_cos_lanes(angle.to_array());
            (F4::from_array(s), F4::from_array(c))
        };
        let (x, y, z) = (rot.x_axis, rot.y_axis, rot.z_axis);
        match k {
            0 => M3::from_cols(x, y.scale(c).add(z.scale(s)), z.scale(c).sub(y.scale(s))),
            1 => M3::from_cols(x.scale(c).sub(z.scale(s)), y, z.scale(c).add(x.scale(s))),
            _ => M3::from_cols(x.scale(c).add(y.scale(s)), y.scale(c).sub(x.scale(s)), z),
        }
    }};
}

/// One group's pose `x`, its origin relative to the reference point `r` and
/// its motion subspace `s` (reference frame), from the parents' poses `xp`
/// (`kinematics::poses`, statement for statement). A macro, not a function:
/// an AVX function is not inlined into its two callers.
macro_rules! group_pose {
    ($st:expr, $xp:expr, $origin:expr, $q:expr) => {{
        let (st, xp): (&GroupStep, &Transform4) = ($st, $xp);
        // The joint frame: parent pose ∘ placement, with the same skips.
        let rot_j = if st.rotates {
            xp.rot.mul_mat3(st.placement.rot)
        } else {
            xp.rot
        };
        let trans_j = if st.translates {
            xp.rot.mul_vec3(st.placement.trans).add(xp.trans)
        } else {
            xp.trans
        };
        let qi = gather($q, &st.idx_q);
        let col = rot_j.col(st.axis);
        let x = Transform4::new(
            rotate_about_axis!(rot_j, st.axis, F4::splat(st.sign).mul(qi)),
            trans_j,
        );
        let aw = if st.sign > 0.0 { col } else { col.neg() };
        let r = x.trans.sub($origin);
        (x, r, Motion4::new(r.cross(aw), aw))
    }};
}

/// The world position and velocity of one point on each leg's last body
/// (`points[k]` in the frame of `plan.groups.last()[k]`), from the base's
/// pose `base`, the reference point `origin` and the base's velocity
/// `vel0`: the chain of [`poses_legs`] kept in registers, nothing stored,
/// then `Data::body_point_world` and `Data::body_point_velocity` per lane.
/// The same bits as those after a full forward kinematics.
#[target_feature(enable = "avx")]
pub(crate) fn leg_end_points(
    plan: &LegLanes,
    base: &Transform,
    origin: DVec3,
    vel0: Motion,
    q: &[f64],
    v: &[f64],
    points: [DVec3; LEGS],
) -> ([DVec3; LEGS], [DVec3; LEGS]) {
    let origin = V3::splat(origin);
    let mut xp = Transform4::new(M3::splat(base.rot), V3::splat(base.trans));
    let mut vp = Motion4::splat(vel0);
    for st in &plan.steps {
        let (x, _, s) = group_pose!(st, &xp, origin, q);
        vp = vp.add(s.scale(gather(v, &st.idx_v)));
        xp = x;
    }
    let p = xp.transform_point(V3::from_lanes(points));
    let pv = vp.lin.add(vp.ang.cross(p.sub(origin)));
    (p.lanes(), pv.lanes())
}

/// The legs' part of forward kinematics (`kinematics::poses`), after the
/// base's (`data.pose[0]`, `data.origin` and, with `v`, `data.vel[0]` set):
/// poses, motion subspaces, inertias (unless `data` is kinematics-only) and
/// velocities of every leg body. Poses and velocities go to the per-body
/// arrays, and so do the subspaces and inertias: every field forward
/// kinematics fills is valid after it, whichever path ran. With velocities
/// and inertias, the groups' subspaces, inertias and velocities are also
/// kept in `data`'s lane cache, for ABA, RNEA and the mass sums in lanes
/// (no gather).
#[target_feature(enable = "avx")]
pub(crate) fn poses_legs(plan: &LegLanes, data: &mut Data, q: &[f64], v: Option<&[f64]>) {
    let base = data.pose[0];
    let origin = V3::splat(data.origin);
    let mut xp = Transform4::new(M3::splat(base.rot), V3::splat(base.trans));
    let mut vp = Motion4::splat(data.vel[0]);
    let with_inertia = !data.inertia_ref.is_empty();
    // The per-body arrays as slices of one known length, and each group's
    // four bodies checked against it once: the stores below then index
    // without bounds checks (16 per group before).
    let n = data.pose.len();
    let pose = &mut data.pose[..n];
    let s_all = &mut data.s[..n];
    let vel = &mut data.vel[..n];
    // (an `if`, not `bool::then`: that one is not inlined into this AVX
    // function and cost a call, about 25 instructions per step)
    let mut inertia_ref = if with_inertia {
        Some(&mut data.inertia_ref[..n])
    } else {
        None
    };
    // The lane cache, when this call fills every entry it holds.
    let ng = plan.groups.len();
    let cache = &mut data.lanes.groups;
    let fill = with_inertia && v.is_some() && cache.len() == ng;
    let cache = &mut cache[..if fill { ng } else { 0 }];
    for (g, (grp, st)) in plan.groups.iter().zip(&plan.steps).enumerate() {
        let bodies = *grp;
        assert!(bodies.iter().all(|&i| i < n), "leg bodies within the model");
        let (x, r, s) = group_pose!(st, &xp, origin, q);
        let xs = x.lanes();
        for k in 0..LEGS {
            pose[bodies[k]] = xs[k];
        }
        let ss = s.lanes();
        for k in 0..LEGS {
            s_all[bodies[k]] = ss[k];
        }
        if fill {
            cache[g].s = s;
        }
        // (a kinematics-only `Data` has no reference inertias)
        if let Some(ir) = inertia_ref.as_deref_mut() {
            let inertia = st.inertia.transformed(&Transform4::new(x.rot, r));
            if fill {
                cache[g].inertia = inertia;
            }
            let (mass, com, ic) = (
                inertia.mass.to_array(),
                inertia.com.lanes(),
                inertia.inertia_com.lanes(),
            );
            for k in 0..LEGS {
                ir[bodies[k]] = RigidInertia::new(mass[k], com[k], ic[k]);
            }
        }
        if let Some(v) = v {
            let vel_g = vp.add(s.scale(gather(v, &st.idx_v)));
            let vs = vel_g.lanes();
            for k in 0..LEGS {
                vel[bodies[k]] = vs[k];
            }
            if fill {
                cache[g].v = vel_g;
            }
            vp = vel_g;
        }
        xp = x;
    }
    data.lanes.valid = fill;
}

/// Per leg (lane `k`), over its bodies in group order from `0.0`: `Σ m`,
/// `Σ m c` and `Σ m (v + ω × c)` (`c` the CoM relative to the reference
/// point), as `[m, mc.x, mc.y, mc.z, p.x, p.y, p.z][k]`, from the lane
/// cache `data` holds (`data.lanes.valid`), for
/// `com::com_and_velocity_by_legs`; [`crate::com::leg_mass_sums_scalar`]
/// gives the same bits. (Summed inside [`poses_legs`]' chain, the sums'
/// registers pushed the chain's values to the stack: about 215
/// instructions more per call, on every forward kinematics.)
#[target_feature(enable = "avx")]
pub(crate) fn leg_mass_sums(data: &Data) -> [[f64; LEGS]; 7] {
    let zero = F4::splat(0.0);
    let (mut m, mut mc, mut p) = (zero, V3::new(zero, zero, zero), V3::new(zero, zero, zero));
    for gk in &data.lanes.groups {
        let (inertia, v) = (&gk.inertia, &gk.v);
        mc = mc.add(inertia.com.scale(inertia.mass));
        m = m.add(inertia.mass);
        p = p.add(v.lin.add(v.ang.cross(inertia.com)).scale(inertia.mass));
    }
    [
        m.to_array(),
        mc.x.to_array(),
        mc.y.to_array(),
        mc.z.to_array(),
        p.x.to_array(),
        p.y.to_array(),
        p.z.to_array(),
    ]
}

/// The forces `f[i]` of the bodies `grp` in lanes, element by element:
/// `Force4::from_lanes` on copies of the four forces went through the stack
/// and back with shuffles (about 70 instructions a group, now 30).
#[inline(always)]
fn gather_forces(f: &[Force], grp: &[usize; LEGS]) -> Force4 {
    let [a, b, c, d] = *grp;
    let (fa, fb, fc, fd) = (&f[a], &f[b], &f[c], &f[d]);
    Force4::new(
        gather_v3([&fa.lin, &fb.lin, &fc.lin, &fd.lin]),
        gather_v3([&fa.ang, &fb.ang, &fc.ang, &fd.ang]),
    )
}

/// ABA's pass 1 for the base (`aba::aba_passes`): its rigid inertia and
/// bias force, minus the external force if any. Scalar code kept out of the
/// AVX function: there LLVM packs it with VEX `vmovq` register moves, which
/// valgrind 3.19 (callgrind, for instruction counts) cannot decode.
#[inline(never)]
fn base_pass1(inertia: &RigidInertia, vi: Motion, f_ext: Option<Force>) -> (Sym6, Force) {
    let mut p = vi.cross_force(inertia.mul_motion(vi));
    if let Some(f) = f_ext {
        p -= f;
    }
    (inertia.to_sym6(), p)
}

/// ABA's three passes after forward kinematics, legs in lanes
/// (`aba::aba_passes`): fills `ddq`, the base's `acc` and, with `body_acc`,
/// the legs' `acc`; ABA's per-body workspace
/// (`ia`, `pa`, `u`, `d_inv`, `u_tau`, `c`) is in the thread's per-group
/// workspace and locals instead.
#[target_feature(enable = "avx")]
pub(crate) fn aba_passes_legs(
    model: &Model,
    plan: &LegLanes,
    data: &mut Data,
    v: &[f64],
    tau: &[f64],
    use_external: bool,
    body_acc: bool,
) {
    let n = model.nbodies;
    let nv = model.nv;
    let groups = &plan.groups[..];
    let ng = groups.len();
    let armature = &model.armature[..nv];
    let (v, tau) = (&v[..nv], &tau[..nv]);
    let f_ext = &data.f_ext[..n];
    // ABA's per-group workspace, from pass 2 to pass 3 of this call only.
    let (mut work_all, mut kin_all) = take_group_aba(ng);
    let work = &mut work_all[..ng];
    // The groups' subspaces and inertias, read in place: from the lane
    // cache, else gathered once into this thread's scratch. (Merged into one
    // by-value result per group, the cached ones were copied to the stack.)
    let kin: &[GroupKinematics] = if data.lanes.valid {
        &data.lanes.groups[..ng]
    } else {
        let scratch = &mut kin_all[..ng];
        for (k, grp) in scratch.iter_mut().zip(groups) {
            *k = gather_kinematics(grp, data);
        }
        scratch
    };
    // Pass 1 of the base; its children's terms are added below.
    let (mut ia0, mut pa0) = base_pass1(
        &data.inertia_ref[0],
        data.vel[0],
        use_external.then(|| f_ext[0]),
    );
    // Pass 2 from the feet to the hips, with pass 1 of each group on the way:
    // a body's own Iᴬ and pᴬ, then its one child's term added, as the
    // general path's `+=` does. Iᴬ stays in `ia`, in memory: the feet's own,
    // then each parent's own plus its child's downdated term, in place.
    let one = F4::splat(1.0);
    let mut ia = match kin.last() {
        Some(k) => k.inertia.to_sym6(),
        None => Sym6x4::default(),
    };
    let mut child_pa: Option<Force4> = None;
    for g in (0..ng).rev() {
        let grp = &groups[g];
        let st = &plan.steps[g];
        let GroupKinematics { s, inertia, v: vi } = &kin[g];
        let vi = *vi;
        let mut pai = vi.cross_force(inertia.mul_motion(vi));
        if use_external && data.external_force_on_any(grp) {
            pai = pai.sub(gather_forces(f_ext, grp));
        }
        // one check for the gathers of v, armature and tau below
        assert_joints_within(&st.idx_v, nv);
        let c = vi.cross(s.scale(gather(v, &st.idx_v)));
        if let Some(cpa) = child_pa {
            pai = pai.add(cpa);
        }
        let u = sym6_mul_motion(&ia, s);
        let d_inv = one.div(s.dot(u).add(gather(armature, &st.idx_v)));
        let ut = gather(tau, &st.idx_v).sub(s.dot(pai));
        let ia_c = sym6_mul_motion(&ia, &c);
        let pa = pai.add(ia_c).add(u.scale(ut.sub(c.dot(u)).mul(d_inv)));
        work[g] = GroupAba {
            u,
            d_inv,
            u_tau: ut,
            c,
        };
        downdate_into(
            &mut ia,
            &u,
            d_inv,
            g.checked_sub(1).map(|p| &kin[p].inertia),
        );
        child_pa = Some(pa);
    }
    // The hips' terms into the base, in decreasing body index (lane 3 first),
    // as the general path's reverse depth order adds them.
    if let Some(pa) = child_pa {
        add_hips_into_base(&mut ia0, &mut pa0, &ia, &pa);
    }
    // Pass 3: accelerations, root to leaves; gravity as a fictitious upward
    // acceleration of the base.
    let a_grav = Motion::new(model.gravity, DVec3::ZERO);
    let a0 = match model.joint_type[0] {
        JointType::Free => {
            let r = data.pose[0].rot;
            let applied = Force::new(
                r * DVec3::new(tau[0], tau[1], tau[2]),
                r * DVec3::new(tau[3], tau[4], tau[5]),
            );
            let rhs = applied - pa0;
            match ia0.solve(rhs) {
                Some(a) => a,
                None => Motion::new(DVec3::NAN, DVec3::NAN),
            }
        }
        _ => -a_grav,
    };
    // true accelerations are a' + a_grav
    data.acc[0] = a0 + a_grav;
    let a_grav_l = Motion4::splat(a_grav);
    let mut a_parent = Motion4::splat(a0);
    let acc = &mut data.acc[..n];
    let ddq = &mut data.ddq[..nv];
    for (((grp, st), w), k) in groups.iter().zip(&plan.steps).zip(work.iter()).zip(kin) {
        let a = a_parent.add(w.c);
        let qdd = w
            .u_tau
            .sub(w.u.lin.dot(a.lin))
            .sub(w.u.ang.dot(a.ang))
            .mul(w.d_inv);
        let a_i = a.add(k.s.scale(qdd));
        let qdds = qdd.to_array();
        assert_joints_within(&st.idx_v, nv);
        for k in 0..LEGS {
            ddq[st.idx_v[k]] = qdds[k];
        }
        if body_acc {
            let accs = a_i.add(a_grav_l).lanes();
            for k in 0..LEGS {
                acc[grp[k]] = accs[k];
            }
        }
        a_parent = a_i;
    }
    if model.joint_type[0] == JointType::Free {
        let rt = data.pose[0].rot.transpose();
        let a0_true = a0 + a_grav;
        let al = rt * a0_true.lin;
        let aa = rt * a0_true.ang;
        data.ddq[..6].copy_from_slice(&[al.x, al.y, al.z, aa.x, aa.y, aa.z]);
    }
    give_back_group_aba((work_all, kin_all));
}

/// `Iᴬ v` for one group, `ia` read from memory. Like [`downdate_into`] it
/// is inlined: rustc (1.95) drops `#[inline(never)]` on `#[target_feature]`
/// functions, and kept out of line (`#[cold]`) both made 256 robots on 2
/// threads 2.4 % slower (six pairs, 2026-11-27). (When the attribute was
/// written, inlining had kept Iᴬ's 27 registers live across the group.)
#[target_feature(enable = "avx")]
fn sym6_mul_motion(ia: &Sym6x4, v: &Motion4) -> Force4 {
    ia.mul_motion(*v)
}

/// ABA's downdate of one group in place: `ia ← own + (ia − U Uᵀ/D)`, the
/// parent's Iᴬ (its own rigid inertia `own` plus its one child's term, in
/// the general path's order), or the term alone for the hips (`own` none).
/// Inlined (see [`sym6_mul_motion`]).
#[target_feature(enable = "avx")]
fn downdate_into(ia: &mut Sym6x4, u: &Force4, d_inv: F4, own: Option<&Inertia4>) {
    let ul = u.lin.scale(d_inv);
    let ua = u.ang.scale(d_inv);
    let term = Sym6x4 {
        m: ia.m.sub(outer(ul, u.lin)),
        h: ia.h.sub(outer(ua, u.lin)),
        i: ia.i.sub(outer(ua, u.ang)),
    };
    *ia = match own {
        Some(o) => o.to_sym6().add(term),
        None => term,
    };
}

/// `ia0 += Σ term` and `pa0 += Σ pa` over the lanes, lane 3 first, each
/// element's sum in that order as the scalar `+=` per lane gives it. Four
/// elements at a time: their 4×4 block of (element, lane) is transposed so
/// that one AVX add adds one lane's term to four elements.
#[inline]
#[target_feature(enable = "avx")]
fn add_hips_into_base(ia0: &mut Sym6, pa0: &mut Force, term: &Sym6x4, pa: &Force4) {
    let m3 = |m: &M3| {
        let (x, y, z) = (m.x_axis, m.y_axis, m.z_axis);
        [x.x, x.y, x.z, y.x, y.y, y.z, z.x, z.y, z.z]
    };
    let (tm, th, ti) = (m3(&term.m), m3(&term.h), m3(&term.i));
    let zero = F4::splat(0.0);
    let lanes: [F4; 36] = [
        tm[0], tm[1], tm[2], tm[3], tm[4], tm[5], tm[6], tm[7], tm[8], //
        th[0], th[1], th[2], th[3], th[4], th[5], th[6], th[7], th[8], //
        ti[0], ti[1], ti[2], ti[3], ti[4], ti[5], ti[6], ti[7], ti[8], //
        pa.lin.x, pa.lin.y, pa.lin.z, pa.ang.x, pa.ang.y, pa.ang.z, zero, zero, zero,
    ];
    let (bm, bh, bi) = (
        ia0.m.to_cols_array(),
        ia0.h.to_cols_array(),
        ia0.i.to_cols_array(),
    );
    let (bl, ba) = (pa0.lin, pa0.ang);
    let mut base: [f64; 36] = [
        bm[0], bm[1], bm[2], bm[3], bm[4], bm[5], bm[6], bm[7], bm[8], //
        bh[0], bh[1], bh[2], bh[3], bh[4], bh[5], bh[6], bh[7], bh[8], //
        bi[0], bi[1], bi[2], bi[3], bi[4], bi[5], bi[6], bi[7], bi[8], //
        bl.x, bl.y, bl.z, ba.x, ba.y, ba.z, 0.0, 0.0, 0.0,
    ];
    for (b, t) in base.chunks_exact_mut(LEGS).zip(lanes.chunks_exact(LEGS)) {
        let by_lane = F4::transpose([t[0], t[1], t[2], t[3]]);
        let mut sum = F4::from_array([b[0], b[1], b[2], b[3]]);
        for k in (0..LEGS).rev() {
            sum = sum.add(by_lane[k]);
        }
        b.copy_from_slice(&sum.to_array());
    }
    let mat = |k: usize| glam::DMat3::from_cols_slice(&base[9 * k..9 * k + 9]);
    (ia0.m, ia0.h, ia0.i) = (mat(0), mat(1), mat(2));
    pa0.lin = DVec3::new(base[27], base[28], base[29]);
    pa0.ang = DVec3::new(base[30], base[31], base[32]);
}

/// Deepest legs [`rnea_passes_legs`] takes (its per-group forces live on
/// the stack); deeper ones run the general path.
pub(crate) const RNEA_MAX_GROUPS: usize = 8;

/// RNEA's two passes over the legs (`rnea::rnea_from_kinematics`), after
/// the base's acceleration `data.acc[0]` is set. `plan` has at most
/// [`RNEA_MAX_GROUPS`] groups.
///
/// With `FULL`, after the base's force `data.f[0]` is set too: fills the
/// legs' `acc`, `f` and `tau` entries and adds the hips' forces to
/// `data.f[0]` in decreasing body index (lane 3 first), as the general
/// path's reverse loop does (`tau_joints` unused).
///
/// Without `FULL`, only the joint torques, for a caller that reads nothing
/// else (the walker's feed-forward; `use_external` must be false): the same
/// operations in the same order on the legs' forces, so the same bits, but
/// no body's `acc` or `f` is stored and the hips' forces are not summed into
/// the base's; each leg joint `j`'s torque goes to `tau_joints[j − base_nv]`.
/// One function for both, the stores chosen at compile time, so that the
/// passes cannot drift apart and neither pays for the other's branches.
#[target_feature(enable = "avx")]
pub(crate) fn rnea_passes_legs<const FULL: bool>(
    model: &Model,
    plan: &LegLanes,
    data: &mut Data,
    v: &[f64],
    a: &[f64],
    use_external: bool,
    tau_joints: &mut [f64],
) {
    let n = model.nbodies;
    let nv = model.nv;
    let nv0 = model.base_nv();
    let groups = &plan.groups[..];
    let ng = groups.len();
    assert!(ng <= RNEA_MAX_GROUPS, "legs within RNEA's lane workspace");
    debug_assert!(FULL || !use_external, "external forces need the full RNEA");
    let armature = &model.armature[..nv];
    let (v, a) = (&v[..nv], &a[..nv]);
    let tau_joints = &mut tau_joints[..if FULL { 0 } else { nv - nv0 }];
    let mut fs = [Force4::default(); RNEA_MAX_GROUPS];
    let mut ss = [Motion4::default(); RNEA_MAX_GROUPS];
    // Pass 1, hips to feet: acc = acc_p + S q̈ + v × S q̇, f = I acc + v ×* I v.
    let mut a_parent = Motion4::splat(data.acc[0]);
    for (g, (grp, st)) in groups.iter().zip(&plan.steps).enumerate() {
        let (s, inertia, vi) = group_kinematics(g, grp, data);
        let acc = a_parent
            .add(s.scale(gather(a, &st.idx_v)))
            .add(vi.cross(s.scale(gather(v, &st.idx_v))));
        let mut f = inertia
            .mul_motion(acc)
            .add(vi.cross_force(inertia.mul_motion(vi)));
        if FULL {
            if use_external && data.external_force_on_any(grp) {
                f = f.sub(gather_forces(&data.f_ext, grp));
            }
            let accs = acc.lanes();
            let acc_all = &mut data.acc[..n];
            for k in 0..LEGS {
                acc_all[grp[k]] = accs[k];
            }
        }
        fs[g] = f;
        ss[g] = s;
        a_parent = acc;
    }
    // Pass 2, feet to hips: each body's force with its one child's added,
    // then τ = Sᵀ f + armature · q̈.
    let mut child: Option<Force4> = None;
    for g in (0..ng).rev() {
        let (grp, idx_v) = (&groups[g], &plan.steps[g].idx_v);
        let mut f = fs[g];
        if let Some(c) = child {
            f = f.add(c);
        }
        let tau = ss[g]
            .dot(f)
            .add(gather(armature, idx_v).mul(gather(a, idx_v)));
        let taus = tau.to_array();
        if FULL {
            let fl = f.lanes();
            let (tau_all, f_all) = (&mut data.tau[..nv], &mut data.f[..n]);
            for k in 0..LEGS {
                tau_all[idx_v[k]] = taus[k];
                f_all[grp[k]] = fl[k];
            }
        } else {
            for k in 0..LEGS {
                tau_joints[idx_v[k] - nv0] = taus[k];
            }
        }
        child = Some(f);
    }
    if FULL && let Some(c) = child {
        let fl = c.lanes();
        for k in (0..LEGS).rev() {
            data.f[0] += fl[k];
        }
    }
}
