//! Spatial (6-D) algebra after Featherstone, *Rigid Body Dynamics Algorithms* (2008), ch. 2.
//!
//! Conventions, fixed once for the whole engine:
//! - spatial vectors are **angular first**: a motion is `[ω; v]`, a force is `[n; f]`;
//! - a body's vectors are expressed in the body's own axes about the body frame's origin;
//! - a [`Transform`] `X` from frame A to frame B holds `E` (the rotation taking A-coordinates to
//!   B-coordinates) and `r` (B's origin in A-coordinates), i.e. `X = [E 0; -E[r]× E]`;
//! - inertias act on motions and give forces: `f = I v`.
//!
//! Every operation works on 3-D blocks, so no 6x6 product is ever formed in the per-call paths.
//!
//! The types are generic over their scalar ([`Real`]): `f64` by default (`Motion` is
//! `Motion<f64>`), or lanes of independent runs ([`crate::real::F64x`]) for the kernels that
//! evaluate several runs at once; every operation is the same code for both. In optimised
//! builds the small operations are always inlined: over lanes, one left out of line is
//! compiled for the baseline target even when an AVX2 instance of a kernel calls it (with
//! them inlined, four lanes of the satellite's kernel went from 1.7 to 2.4 times one run's
//! throughput; one run's orbit took 0.8 % fewer instructions). Builds with debug assertions
//! (the tests) leave it to the compiler, which keeps the lane kernels' test builds minutes
//! shorter; inlining changes no result.

use crate::real::{Real, mat3};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// 3-vector of `f64`.
pub type Vec3 = Vector3<f64>;
/// 3x3 matrix of `f64`.
pub type Mat3 = Matrix3<f64>;

/// Tolerance on the norm of axes and quaternions given by the user (hinge axes, facet
/// normals, attitudes): within it of 1 they are normalised, beyond it refused. Here, beside
/// the vectors it judges, so that every module that reads them shares it.
pub const UNIT_NORM_TOLERANCE: f64 = 1e-6;

/// The matrix `[a]×` with `[a]× b = a × b`.
///
/// ```
/// use satsim_tree::spatial::{skew, Vec3};
/// let (a, b) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(-1.0, 0.5, 2.0));
/// assert!((skew(&a) * b - a.cross(&b)).norm() < 1e-15);
/// ```
#[cfg_attr(not(debug_assertions), inline(always))]
#[cfg_attr(debug_assertions, inline)]
pub fn skew<T: Real>(a: &Vector3<T>) -> Matrix3<T> {
    let o = T::zero();
    Matrix3::new(o, -a.z, a.y, a.z, o, -a.x, -a.y, a.x, o)
}

/// `[a]× M`, column by column: `a × mⱼ` (cheaper than the product with the matrix `[a]×`).
#[cfg_attr(not(debug_assertions), inline(always))]
#[cfg_attr(debug_assertions, inline)]
pub(crate) fn cross_columns<T: Real>(a: &Vector3<T>, m: &Matrix3<T>) -> Matrix3<T> {
    let col = |j: usize| Vector3::new(m[(0, j)], m[(1, j)], m[(2, j)]);
    Matrix3::from_columns(&[
        mat3::cross(a, &col(0)),
        mat3::cross(a, &col(1)),
        mat3::cross(a, &col(2)),
    ])
}

/// The inverse of a symmetric positive definite 3x3 matrix, `None` unless it is positive
/// definite (a pivot not positive, or NaN). By `M = L D Lᵀ` written out (no square roots,
/// three divisions) and `M⁻¹ = L⁻ᵀ D⁻¹ L⁻¹ = Σₖ uₖ uₖᵀ / dₖ` over the rows `uₖ` of `L⁻¹`:
/// backward stable as a Cholesky factorisation (the pivots are Cholesky's squared), as
/// accurate as nalgebra's Cholesky inverse (tested) at a fraction of its latency.
#[cfg_attr(not(debug_assertions), inline(always))]
#[cfg_attr(debug_assertions, inline)]
pub(crate) fn spd_inverse<T: Real>(m: &Matrix3<T>) -> Option<Matrix3<T>> {
    let [a, b, c, d, e, f] = [
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 1)],
        m[(1, 2)],
        m[(2, 2)],
    ];
    // L = [1 0 0; l1 1 0; l2 l21 1], D = diag(d0, d1, d2).
    let d0 = a;
    let r0 = T::one() / d0;
    let (l1, l2) = (b * r0, c * r0);
    let d1 = d - l1 * b;
    let r1 = T::one() / d1;
    let e1 = e - l2 * b;
    let l21 = e1 * r1;
    let d2 = f - l2 * c - l21 * e1;
    // Written so that a NaN or infinite pivot fails too (on any lane).
    let positive = |x: f64| x > 0.0;
    if !(d0.all(positive)
        && d1.all(positive)
        && d2.all(positive)
        && (d0 + d1 + d2).all(f64::is_finite))
    {
        return None;
    }
    let r2 = T::one() / d2;
    // Rows of L⁻¹: (1, 0, 0), (−l1, 1, 0), (w, −l21, 1) with w = l1 l21 − l2.
    let w = l1 * l21 - l2;
    let (wr2, mr2) = (w * r2, l21 * r2);
    let x00 = r0 + l1 * l1 * r1 + w * wr2;
    let x01 = -l1 * r1 - l21 * wr2;
    let x02 = wr2;
    let x11 = r1 + l21 * mr2;
    let x12 = -mr2;
    Some(Matrix3::new(x00, x01, x02, x01, x11, x12, x02, x12, r2))
}

/// A spatial motion vector (velocity, acceleration, motion subspace column): `[ω; v]`.
///
/// ```
/// use satsim_tree::spatial::{Motion, Vec3};
/// let v = Motion::new(Vec3::z(), Vec3::x());
/// assert_eq!(v.cross_motion(&v), Motion::zero()); // v ×m v = 0
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Motion<T: Real = f64> {
    /// Angular part ω (rad/s, rad/s²).
    pub ang: Vector3<T>,
    /// Linear part v of the frame origin (m/s, m/s²).
    pub lin: Vector3<T>,
}

/// A spatial force vector: `[n; f]`, the moment `n` about the frame origin and the force `f`.
///
/// ```
/// use satsim_tree::spatial::{Force, Motion, Vec3};
/// let f = Force::new(Vec3::new(0.0, 0.0, 2.0), Vec3::zeros());
/// let v = Motion::new(Vec3::z(), Vec3::zeros());
/// assert_eq!(v.dot(&f), 2.0); // power
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Force<T: Real = f64> {
    /// Moment about the frame origin (N m).
    pub ang: Vector3<T>,
    /// Force (N).
    pub lin: Vector3<T>,
}

impl<T: Real> Motion<T> {
    /// A motion from its angular and linear parts.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn new(ang: Vector3<T>, lin: Vector3<T>) -> Self {
        Self { ang, lin }
    }
    /// The zero motion.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn zero() -> Self {
        Self::default()
    }
    /// `self ×m m` (Featherstone's `crm(v) m`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn cross_motion(&self, m: &Motion<T>) -> Motion<T> {
        Motion {
            ang: mat3::cross(&self.ang, &m.ang),
            lin: mat3::cross(&self.ang, &m.lin) + mat3::cross(&self.lin, &m.ang),
        }
    }
    /// `self ×* f` (Featherstone's `crf(v) f`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn cross_force(&self, f: &Force<T>) -> Force<T> {
        Force {
            ang: mat3::cross(&self.ang, &f.ang) + mat3::cross(&self.lin, &f.lin),
            lin: mat3::cross(&self.ang, &f.lin),
        }
    }
    /// The scalar product with a force (power).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn dot(&self, f: &Force<T>) -> T {
        self.ang.dot(&f.ang) + self.lin.dot(&f.lin)
    }
    /// As a 6-vector `[ω; v]`.
    pub fn to_vector(&self) -> Vector6<T> {
        Vector6::new(
            self.ang.x, self.ang.y, self.ang.z, self.lin.x, self.lin.y, self.lin.z,
        )
    }
    /// From the first six entries of a slice `[ω; v]`.
    ///
    /// # Panics
    /// If the slice has fewer than six entries (a programming error, not user data).
    pub fn from_slice(s: &[T]) -> Self {
        Self::new(
            Vector3::new(s[0], s[1], s[2]),
            Vector3::new(s[3], s[4], s[5]),
        )
    }
    /// As an array `[ω; v]`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn to_array(&self) -> [T; 6] {
        let (a, l) = (&self.ang, &self.lin);
        [a.x, a.y, a.z, l.x, l.y, l.z]
    }
}

impl<T: Real> Force<T> {
    /// A force from its moment and force parts.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn new(ang: Vector3<T>, lin: Vector3<T>) -> Self {
        Self { ang, lin }
    }
    /// The zero force.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn zero() -> Self {
        Self::default()
    }
    /// As a 6-vector `[n; f]`.
    pub fn to_vector(&self) -> Vector6<T> {
        Vector6::new(
            self.ang.x, self.ang.y, self.ang.z, self.lin.x, self.lin.y, self.lin.z,
        )
    }
    /// As an array `[n; f]`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn to_array(&self) -> [T; 6] {
        let (a, l) = (&self.ang, &self.lin);
        [a.x, a.y, a.z, l.x, l.y, l.z]
    }
    /// From the first six entries of a slice `[n; f]`.
    ///
    /// # Panics
    /// If the slice has fewer than six entries (a programming error, not user data).
    pub fn from_slice(s: &[T]) -> Self {
        Self::new(
            Vector3::new(s[0], s[1], s[2]),
            Vector3::new(s[3], s[4], s[5]),
        )
    }
}

macro_rules! linear_ops {
    ($t:ident) => {
        impl<T: Real> Add for $t<T> {
            type Output = $t<T>;
            #[inline]
            fn add(self, o: $t<T>) -> $t<T> {
                Self {
                    ang: self.ang + o.ang,
                    lin: self.lin + o.lin,
                }
            }
        }
        impl<T: Real> Sub for $t<T> {
            type Output = $t<T>;
            #[inline]
            fn sub(self, o: $t<T>) -> $t<T> {
                Self {
                    ang: self.ang - o.ang,
                    lin: self.lin - o.lin,
                }
            }
        }
        impl<T: Real> AddAssign for $t<T> {
            #[inline]
            fn add_assign(&mut self, o: $t<T>) {
                self.ang += o.ang;
                self.lin += o.lin;
            }
        }
        impl<T: Real> SubAssign for $t<T> {
            #[inline]
            fn sub_assign(&mut self, o: $t<T>) {
                self.ang -= o.ang;
                self.lin -= o.lin;
            }
        }
        impl<T: Real> Neg for $t<T> {
            type Output = $t<T>;
            #[inline]
            fn neg(self) -> $t<T> {
                Self {
                    ang: -self.ang,
                    lin: -self.lin,
                }
            }
        }
        impl<T: Real> Mul<T> for $t<T> {
            type Output = $t<T>;
            #[inline]
            fn mul(self, s: T) -> $t<T> {
                Self {
                    ang: self.ang * s,
                    lin: self.lin * s,
                }
            }
        }
    };
}
linear_ops!(Motion);
linear_ops!(Force);

/// A Plücker transform from frame A (the parent) to frame B (the child): `X = [E 0; -E[r]× E]`.
///
/// ```
/// use satsim_tree::spatial::{Mat3, Motion, Transform, Vec3};
/// // B is A shifted by 1 m along x: a pure spin about A's origin is seen in B
/// // as a spin plus a linear velocity of B's origin.
/// let x = Transform::new(Mat3::identity(), Vec3::x());
/// let v = x.apply_motion(&Motion::new(Vec3::z(), Vec3::zeros()));
/// assert!((v.lin - Vec3::y()).norm() < 1e-15);
/// assert_eq!(x.inv_apply_motion(&v), Motion::new(Vec3::z(), Vec3::zeros()));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform<T: Real = f64> {
    /// `E`: rotates A-coordinates into B-coordinates.
    pub rot: Matrix3<T>,
    /// `r`: B's origin in A-coordinates (m).
    pub trans: Vector3<T>,
}

impl<T: Real> Default for Transform<T> {
    fn default() -> Self {
        Self::identity()
    }
}

impl<T: Real> Transform<T> {
    /// A transform from `E` (A to B coordinates) and `r` (B's origin in A).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn new(rot: Matrix3<T>, trans: Vector3<T>) -> Self {
        Self { rot, trans }
    }
    /// The identity transform.
    pub fn identity() -> Self {
        Self::new(Matrix3::identity(), Vector3::zeros())
    }
    /// `X m`: a motion in A-coordinates expressed in B-coordinates.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn apply_motion(&self, m: &Motion<T>) -> Motion<T> {
        Motion {
            ang: mat3::mul(&self.rot, &m.ang),
            lin: mat3::mul(&self.rot, &(m.lin - mat3::cross(&self.trans, &m.ang))),
        }
    }
    /// `X⁻¹ m`: a motion in B-coordinates expressed in A-coordinates.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn inv_apply_motion(&self, m: &Motion<T>) -> Motion<T> {
        let ang = mat3::tr_mul(&self.rot, &m.ang);
        Motion {
            ang,
            lin: mat3::tr_mul(&self.rot, &m.lin) + mat3::cross(&self.trans, &ang),
        }
    }
    /// `X* f`: a force in A-coordinates expressed in B-coordinates.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn apply_force(&self, f: &Force<T>) -> Force<T> {
        Force {
            ang: mat3::mul(&self.rot, &(f.ang - mat3::cross(&self.trans, &f.lin))),
            lin: mat3::mul(&self.rot, &f.lin),
        }
    }
    /// `Xᵀ f`: a force in B-coordinates expressed in A-coordinates.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn inv_apply_force(&self, f: &Force<T>) -> Force<T> {
        let lin = mat3::tr_mul(&self.rot, &f.lin);
        Force {
            ang: mat3::tr_mul(&self.rot, &f.ang) + mat3::cross(&self.trans, &lin),
            lin,
        }
    }
    /// `self * other`: first `other` (A to B), then `self` (B to C); gives A to C.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn compose(&self, other: &Transform<T>) -> Transform<T> {
        Transform {
            rot: mat3::mul_mat(&self.rot, &other.rot),
            trans: other.trans + mat3::tr_mul(&other.rot, &self.trans),
        }
    }
}

impl Transform {
    /// The 6x6 motion-transform matrix.
    pub fn to_matrix(&self) -> Matrix6<f64> {
        let mut x = Matrix6::zeros();
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.rot);
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.rot);
        x.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(-self.rot * skew(&self.trans)));
        x
    }
}

/// The spatial inertia of a rigid body (or a rigid composite) about a frame origin:
/// mass `m`, first moment `h = m c` and rotational inertia `I` about the origin.
///
/// ```
/// use satsim_tree::spatial::{Mat3, Motion, RigidInertia, Vec3};
/// let i = RigidInertia::from_com(2.0, Vec3::new(0.5, 0.0, 0.0), Mat3::identity());
/// // Spinning about the origin moves the centre of mass: linear momentum m ω × c.
/// let f = i.mul_motion(&Motion::new(Vec3::z(), Vec3::zeros()));
/// assert!((f.lin - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct RigidInertia<T: Real = f64> {
    /// Mass (kg).
    pub mass: T,
    /// First moment of mass about the origin, `m c` (kg m).
    pub h: Vector3<T>,
    /// Rotational inertia about the origin (kg m²).
    pub inertia: Matrix3<T>,
}

impl<T: Real> RigidInertia<T> {
    /// From mass, centre of mass `c` and rotational inertia `ic` about the centre of mass.
    pub fn from_com(mass: T, com: Vector3<T>, ic: Matrix3<T>) -> Self {
        let cx = skew(&com);
        Self {
            mass,
            h: com * mass,
            inertia: ic - cx * cx * mass,
        }
    }
    /// `I v`: the momentum of a body moving with `v`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn mul_motion(&self, v: &Motion<T>) -> Force<T> {
        Force {
            ang: mat3::mul(&self.inertia, &v.ang) + mat3::cross(&self.h, &v.lin),
            lin: v.lin * self.mass - mat3::cross(&self.h, &v.ang),
        }
    }
    /// `Xᵀ I X`: this inertia, given in B-coordinates, expressed in A-coordinates
    /// (moves a child's inertia to its parent; Featherstone eq. 2.66 in 3-D blocks).
    ///
    /// Always inlined: CRBA's inward pass is little else, and when the multi-axis chains
    /// grew the crate, LLVM stopped inlining it there (+10 % instructions per mass matrix,
    /// the result returned through memory).
    #[inline(always)]
    pub fn inv_transform(&self, x: &Transform<T>) -> RigidInertia<T> {
        let e = &x.rot;
        let rotated = RigidInertia {
            mass: self.mass,
            h: mat3::tr_mul(e, &self.h),
            inertia: mat3::tr_mul_mat(e, &mat3::mul_mat(&self.inertia, e)),
        };
        rotated.translated(&x.trans)
    }

    /// This inertia (same axes) about a point at `−r` from the origin, i.e. about the origin
    /// of a frame in which this origin lies at `r`: the translation part of
    /// [`RigidInertia::inv_transform`]. Always inlined, as that is (CRBA's inward pass).
    #[inline(always)]
    pub(crate) fn translated(&self, r: &Vector3<T>) -> RigidInertia<T> {
        let h = self.h;
        let hp = h + r * self.mass;
        // I − [r]×[h]× − [h']×[r]×, the skew products by [a]×[b]× = b aᵀ − (a·b) 1.
        let i = self.inertia - h * r.transpose() - r * hp.transpose()
            + Matrix3::from_diagonal_element(r.dot(&h) + r.dot(&hp));
        RigidInertia {
            mass: self.mass,
            h: hp,
            // Symmetric in exact arithmetic; averaging keeps it symmetric to the last bit.
            inertia: (i + i.transpose()) * T::splat(0.5),
        }
    }
}

impl RigidInertia {
    /// The 6x6 matrix `[I [h]×; [h]×ᵀ m1]`.
    pub fn to_matrix(&self) -> Matrix6<f64> {
        ArticulatedInertia::from(*self).to_matrix()
    }
}

impl<T: Real> Add for RigidInertia<T> {
    type Output = RigidInertia<T>;
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn add(self, o: RigidInertia<T>) -> RigidInertia<T> {
        RigidInertia {
            mass: self.mass + o.mass,
            h: self.h + o.h,
            inertia: self.inertia + o.inertia,
        }
    }
}
impl<T: Real> AddAssign for RigidInertia<T> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn add_assign(&mut self, o: RigidInertia<T>) {
        self.mass += o.mass;
        self.h += o.h;
        self.inertia += o.inertia;
    }
}

/// A general symmetric 6x6 inertia `[A B; Bᵀ C]` (articulated-body inertia), in 3x3 blocks.
///
/// ```
/// use satsim_tree::spatial::{ArticulatedInertia, Mat3, RigidInertia, Vec3};
/// let rigid = RigidInertia::from_com(3.0, Vec3::new(0.1, 0.2, 0.3), Mat3::identity());
/// let ia = ArticulatedInertia::from(rigid);
/// assert!((ia.to_matrix() - rigid.to_matrix()).norm() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ArticulatedInertia<T: Real = f64> {
    /// Angular-angular block `A`.
    pub a: Matrix3<T>,
    /// Angular-linear block `B`.
    pub b: Matrix3<T>,
    /// Linear-linear block `C`.
    pub c: Matrix3<T>,
}

impl<T: Real> From<RigidInertia<T>> for ArticulatedInertia<T> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn from(i: RigidInertia<T>) -> Self {
        Self {
            a: i.inertia,
            b: skew(&i.h),
            c: Matrix3::from_diagonal_element(i.mass),
        }
    }
}

impl<T: Real> ArticulatedInertia<T> {
    /// `IA v`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn mul_motion(&self, v: &Motion<T>) -> Force<T> {
        Force {
            ang: mat3::mul(&self.a, &v.ang) + mat3::mul(&self.b, &v.lin),
            lin: mat3::tr_mul(&self.b, &v.ang) + mat3::mul(&self.c, &v.lin),
        }
    }
    /// `IA - u uᵀ / d` for a force-like column `u` (the hinge's projection out of `IA`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn sub_outer(&mut self, u: &Force<T>, inv_d: T) {
        let un = u.ang * inv_d;
        let uf = u.lin * inv_d;
        self.a -= mat3::outer(&un, &u.ang);
        self.b -= mat3::outer(&un, &u.lin);
        self.c -= mat3::outer(&uf, &u.lin);
    }
    /// `self = from − u uᵀ / d`: [`Self::sub_outer`] of `from`, written here.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub(crate) fn set_sub_outer(&mut self, from: &ArticulatedInertia<T>, u: &Force<T>, inv_d: T) {
        let un = u.ang * inv_d;
        let uf = u.lin * inv_d;
        self.a = from.a - mat3::outer(&un, &u.ang);
        self.b = from.b - mat3::outer(&un, &u.lin);
        self.c = from.c - mat3::outer(&uf, &u.lin);
    }
    /// `Xᵀ IA X`: this inertia, given in B-coordinates, expressed in A-coordinates.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn inv_transform(&self, x: &Transform<T>) -> ArticulatedInertia<T> {
        let mut out = ArticulatedInertia::default();
        self.add_inv_transform_to(x, &mut out, None);
        out
    }
    /// `out += Xᵀ IA X`, or `out = start + Xᵀ IA X` with `Some(start)` (ABA's accumulation
    /// into the parent, in place: no 6x6 temporary is returned and copied).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub(crate) fn add_inv_transform_to(
        &self,
        x: &Transform<T>,
        out: &mut ArticulatedInertia<T>,
        start: Option<&ArticulatedInertia<T>>,
    ) {
        let e = &x.rot;
        let a = mat3::tr_mul_mat(e, &mat3::mul_mat(&self.a, e));
        let b = mat3::tr_mul_mat(e, &mat3::mul_mat(&self.b, e));
        let c = mat3::tr_mul_mat(e, &mat3::mul_mat(&self.c, e));
        add_translated(&a, &b, &c, &x.trans, out, start);
    }
}

/// `out += [1 [r]×; 0 1] [A B; Bᵀ C] [1 0; −[r]× 1]` (or `out = start + ...` with
/// `Some(start)`), the translation part of [`ArticulatedInertia::inv_transform`]: the inertia
/// `[A B; Bᵀ C]` about the origin of a frame with the same axes in which its origin lies at
/// `r`, added to `out`.
#[cfg_attr(not(debug_assertions), inline(always))]
#[cfg_attr(debug_assertions, inline)]
pub(crate) fn add_translated<T: Real>(
    a: &Matrix3<T>,
    b: &Matrix3<T>,
    c: &Matrix3<T>,
    r: &Vector3<T>,
    out: &mut ArticulatedInertia<T>,
    start: Option<&ArticulatedInertia<T>>,
) {
    // (Over lanes: taken when every lane's origins coincide. A batch whose lanes differ
    // there is not formed: `satsim-satellite`'s kernel checks it when it gathers lanes.)
    let (na, nb) = if *r == Vector3::zeros() {
        // Coincident origins (a zero-length gimbal link): a pure rotation.
        (*a, *b)
    } else {
        // With M [r]× = −([r]× Mᵀ)ᵀ.
        let nb = b + cross_columns(r, c);
        let na =
            a + cross_columns(r, &b.transpose()) + cross_columns(r, &nb.transpose()).transpose();
        (na, nb)
    };
    add_blocks(&na, &nb, c, out, start);
}

/// `out += [A B; Bᵀ C]` (`out = start + [A B; Bᵀ C]` with `Some(start)`): the last step of
/// every inertia transform that accumulates into a parent. Always inlined: left to the
/// heuristics it stopped being inlined into [`add_translated`] once the flexible algorithms
/// joined the crate, +1.0 % instructions on the orbit benchmark (callgrind, 600 s).
#[inline(always)]
pub(crate) fn add_blocks<T: Real>(
    a: &Matrix3<T>,
    b: &Matrix3<T>,
    c: &Matrix3<T>,
    out: &mut ArticulatedInertia<T>,
    start: Option<&ArticulatedInertia<T>>,
) {
    match start {
        Some(s) => {
            out.a = s.a + a;
            out.b = s.b + b;
            out.c = s.c + c;
        }
        None => {
            out.a += a;
            out.b += b;
            out.c += c;
        }
    }
}

impl<T: Real> ArticulatedInertia<T> {
    /// `IA⁻¹ f`: the motion `[α; a]` with `IA [α; a] = f`, by the Schur complement
    /// `S = A − B C⁻¹ Bᵀ` (no 6x6 matrix): `α = S⁻¹ (f_ang − B C⁻¹ f_lin)`,
    /// `a = C⁻¹ (f_lin − Bᵀ α)`. `None` unless `IA` is positive definite (then `C` and `S`
    /// are, and conversely).
    ///
    /// The two 3x3 inverses are written out (`L D Lᵀ`, no square roots),
    /// where nalgebra's generic Cholesky factorisations and solves ran out of line: ABA
    /// ends every right-hand side with this solve, and a perf profile of the peer orbit put
    /// that form at 12 % of the run.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn solve(&self, f: &Force<T>) -> Option<Motion<T>> {
        // nalgebra's products, through `mat3` so that they stay inline over lanes.
        let c_inv = spd_inverse(&self.c)?;
        let bt = self.b.transpose();
        let bc = mat3::mul_mat(&self.b, &c_inv); // B C⁻¹
        let schur = self.a - mat3::mul_mat(&bc, &bt);
        let ang = mat3::mul(&spd_inverse(&schur)?, &(f.ang - mat3::mul(&bc, &f.lin)));
        Some(Motion::new(
            ang,
            mat3::mul(&c_inv, &(f.lin - mat3::mul(&bt, &ang))),
        ))
    }
}

impl ArticulatedInertia {
    /// The full 6x6 matrix.
    pub fn to_matrix(&self) -> Matrix6<f64> {
        let mut m = Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.a);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.b);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.b.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.c);
        m
    }
}

impl<T: Real> AddAssign for ArticulatedInertia<T> {
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn add_assign(&mut self, o: ArticulatedInertia<T>) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }
}

/// Rodrigues' formula: the rotation by `angle` about the unit vector `axis`.
///
/// ```
/// use satsim_tree::spatial::{rotation_about, Vec3};
/// let r = rotation_about(&Vec3::z(), std::f64::consts::FRAC_PI_2);
/// assert!((r * Vec3::x() - Vec3::y()).norm() < 1e-15);
/// ```
#[cfg_attr(not(debug_assertions), inline(always))]
#[cfg_attr(debug_assertions, inline)]
pub fn rotation_about<T: Real>(axis: &Vector3<T>, angle: T) -> Matrix3<T> {
    // 1 + s [a]× + (1 − c) [a]×², with [a]×² = a aᵀ − 1 for a unit axis.
    let (s, c) = angle.sin_cos(); // libm's, as the coordinate-axis transforms (`axis.rs`)
    let (a, t) = (axis * s, axis * (T::one() - c));
    let [x, y, z] = [axis.x, axis.y, axis.z];
    Matrix3::new(
        c + t.x * x,
        t.x * y - a.z,
        t.x * z + a.y,
        t.y * x + a.z,
        c + t.y * y,
        t.y * z - a.x,
        t.z * x - a.y,
        t.z * y + a.x,
        c + t.z * z,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (Transform, Motion, Force, RigidInertia) {
        let e = rotation_about(&Vec3::new(1.0, 2.0, 2.0).normalize(), 0.7);
        let x = Transform::new(e, Vec3::new(0.3, -1.2, 0.5));
        let m = Motion::new(Vec3::new(0.1, -0.4, 0.9), Vec3::new(2.0, 0.3, -1.0));
        let f = Force::new(Vec3::new(-0.5, 1.0, 0.2), Vec3::new(0.7, 0.1, 3.0));
        let ic = Mat3::new(2.0, 0.1, 0.2, 0.1, 3.0, -0.3, 0.2, -0.3, 4.0);
        let i = RigidInertia::from_com(5.0, Vec3::new(0.2, -0.1, 0.4), ic);
        (x, m, f, i)
    }

    #[test]
    fn block_ops_match_6x6_matrices() {
        let (x, m, f, i) = sample();
        let xm = x.to_matrix();
        let xf = xm.try_inverse().unwrap().transpose(); // X* = X^-T
        assert!((x.apply_motion(&m).to_vector() - xm * m.to_vector()).norm() < 1e-13);
        assert!((x.apply_force(&f).to_vector() - xf * f.to_vector()).norm() < 1e-13);
        assert!(
            (x.inv_apply_force(&f).to_vector() - xm.transpose() * f.to_vector()).norm() < 1e-13
        );
        let back = x.inv_apply_motion(&x.apply_motion(&m));
        assert!((back.to_vector() - m.to_vector()).norm() < 1e-13);
        assert!((i.mul_motion(&m).to_vector() - i.to_matrix() * m.to_vector()).norm() < 1e-13);
        let ip = i.inv_transform(&x).to_matrix();
        assert!((ip - xm.transpose() * i.to_matrix() * xm).norm() < 1e-12);
        let ia = ArticulatedInertia::from(i).inv_transform(&x);
        assert!((ia.to_matrix() - ip).norm() < 1e-12);
        let at_origin = Transform::new(x.rot, Vec3::zeros());
        let ir = ArticulatedInertia::from(i)
            .inv_transform(&at_origin)
            .to_matrix();
        let xr = at_origin.to_matrix();
        assert!((ir - xr.transpose() * i.to_matrix() * xr).norm() < 1e-12);
        let a = ia.solve(&f).unwrap();
        assert!((ia.to_matrix() * a.to_vector() - f.to_vector()).norm() < 1e-12);
        assert_eq!(ArticulatedInertia::default().solve(&f), None);
    }

    #[test]
    fn spd_inverse_agrees_with_cholesky_and_refuses_indefinite_matrices() {
        // Random rotations of diagonal matrices with condition numbers 1 to 1e8, at scales
        // from 1e-120 to 1e120: the cofactor inverse is as close to the exact inverse as
        // nalgebra's Cholesky inverse is (both err by up to about κ ε).
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..300 {
            let kappa = 10f64.powf(8.0 * (k % 10) as f64 / 9.0);
            let scale = 10f64.powi(-120 + 24 * (k % 11));
            let axis = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let r = rotation_about(&axis, 6.0 * next());
            let d = Vec3::new(1.0, kappa.sqrt(), kappa) * scale;
            let m = r * Mat3::from_diagonal(&d) * r.transpose();
            let m = (m + m.transpose()) * 0.5;
            let exact = r * Mat3::from_diagonal(&d.map(|x| 1.0 / x)) * r.transpose();
            let err = |inv: Mat3| (inv - exact).norm() / exact.norm();
            let ours = err(spd_inverse(&m).expect("positive definite"));
            let cholesky = err(m.cholesky().unwrap().inverse());
            assert!(
                ours < 4.0 * cholesky.max(kappa * f64::EPSILON),
                "κ {kappa:e}, scale {scale:e}: {ours:e} against Cholesky's {cholesky:e}"
            );
        }
        let indefinite = [
            Mat3::from_diagonal(&Vec3::new(1.0, -1.0, 1.0)),
            Mat3::from_diagonal(&Vec3::new(-1.0, -1.0, 3.0)), // positive determinant
            Mat3::from_diagonal(&Vec3::new(1.0, 1.0, 0.0)),
            Mat3::zeros(),
            Mat3::from_element(f64::NAN),
            Mat3::from_diagonal(&Vec3::new(1.0, f64::INFINITY, 1.0)),
        ];
        for m in indefinite {
            assert_eq!(spd_inverse(&m), None, "{m}");
        }
    }

    #[test]
    fn rodrigues_matches_nalgebra() {
        for (axis, angle) in [
            (Vec3::new(1.0, 2.0, 2.0), 0.7),
            (Vec3::new(-0.3, 0.1, 0.9), -2.9),
        ] {
            let axis = axis.normalize();
            let r =
                nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), angle);
            assert!((rotation_about(&axis, angle) - r.matrix()).norm() < 1e-15);
        }
    }

    #[test]
    fn cross_products_match_featherstone() {
        let (_, m, f, _) = sample();
        let v = Motion::new(Vec3::new(0.3, 0.2, -0.1), Vec3::new(1.0, -2.0, 0.5));
        let mut crm = Matrix6::zeros();
        crm.fixed_view_mut::<3, 3>(0, 0).copy_from(&skew(&v.ang));
        crm.fixed_view_mut::<3, 3>(3, 3).copy_from(&skew(&v.ang));
        crm.fixed_view_mut::<3, 3>(3, 0).copy_from(&skew(&v.lin));
        let crf = -crm.transpose();
        assert!((v.cross_motion(&m).to_vector() - crm * m.to_vector()).norm() < 1e-14);
        assert!((v.cross_force(&f).to_vector() - crf * f.to_vector()).norm() < 1e-14);
    }

    #[test]
    fn compose_is_matrix_product() {
        let (x, ..) = sample();
        let y = Transform::new(rotation_about(&Vec3::y(), -0.4), Vec3::new(1.0, 0.0, 2.0));
        let z = y.compose(&x);
        assert!((z.to_matrix() - y.to_matrix() * x.to_matrix()).norm() < 1e-13);
    }
}
