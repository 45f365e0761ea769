//! The preprint's closed-form `S` and `N` (equation (19)), one function per printed symbol,
//! so that each can be read against the text.
//!
//! Every vector here is in the bus frame `O1x1y1z1` (the preprint's basic frame), at one
//! instant; [`Symbols::new`] brings the parameters there with Table 2. Where the printed
//! text is wrong, the function takes a [`Variant`] (or has an `_as_printed` twin) so that
//! both readings stay evaluable; the errata are listed in `docs/src/preprint/errata.md`.
#![allow(non_snake_case)]

use super::params::PreprintParams;
use super::table2::{Table2, table2};
pub use super::variant::Variant;
use nalgebra::{SMatrix, SVector};
use satsim_tree::spatial::{Mat3, Vec3};

/// `K(a, b)`: the matrix with `K(a, b) y = a × (y × b)`, as printed:
/// `[[a2b2+a3b3, −a2b1, −a3b1], [−a1b2, a1b1+a3b3, −a3b2], [−a1b3, −a2b3, a1b1+a2b2]]`.
pub fn K(a: &Vec3, b: &Vec3) -> Mat3 {
    let (a1, a2, a3) = (a.x, a.y, a.z);
    let (b1, b2, b3) = (b.x, b.y, b.z);
    Mat3::new(
        a2 * b2 + a3 * b3,
        -a2 * b1,
        -a3 * b1,
        -a1 * b2,
        a1 * b1 + a3 * b3,
        -a3 * b2,
        -a1 * b3,
        -a2 * b3,
        a1 * b1 + a2 * b2,
    )
}

/// The state of the system at one instant, as the preprint's equations (19) need it.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct PreprintState {
    /// Hinge angles `φ1..φ5` (rad).
    pub phi: [f64; 5],
    /// `ω1`: the bus angular velocity, bus axes (rad/s).
    pub omega1: Vec3,
    /// `ψ1..ψ5 = φ̇1..φ̇5`: hinge rates (rad/s).
    pub psi: [f64; 5],
    /// `M_u1..M_u5`: hinge torques about the axes, acting on the child (N m).
    pub m_u: [f64; 5],
    /// `M1..M4`: external couples on each body, in that body's own axes (Table 1) (N m).
    pub m_ext: [Vec3; 4],
}

/// The preprint's symbols at one instant, every vector in the bus frame `O1x1y1z1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Symbols {
    /// `m1..m4` (kg) (the preprint's `m_{O1}..m_{O4}`).
    pub m: [f64; 4],
    /// `I1..I4` about each body's centre of mass, bus axes (kg m²).
    pub I: [Mat3; 4],
    /// `a1` (m).
    pub a1: Vec3,
    /// `c2` (m).
    pub c2: Vec3,
    /// `a2` (m).
    pub a2: Vec3,
    /// `c3` (m).
    pub c3: Vec3,
    /// `a3` (m).
    pub a3: Vec3,
    /// `c4` (m).
    pub c4: Vec3,
    /// `e1..e5` (unit).
    pub e: [Vec3; 5],
    /// `ω1` (rad/s).
    pub omega1: Vec3,
    /// `ψ1..ψ5` (rad/s).
    pub psi: [f64; 5],
    /// `M_u1..M_u5` (N m).
    pub M_u: [f64; 5],
    /// `M1..M4` (N m).
    pub M: [Vec3; 4],
}

impl Symbols {
    /// Brings parameters and state to the bus frame with (corrected) Table 2, taking each
    /// vector from the frame in which Table 1 gives it: `I1, a1, M1` bus; `I2, c2, a2, M2`
    /// panel 1; `I3, c3, a3, M3` panel 2; `I4, c4, M4` panel 3; `e_k` from `P_k`.
    pub fn new(p: &PreprintParams, s: &PreprintState) -> Self {
        let t: Table2 = table2(p, &s.phi, Variant::Corrected);
        let rot_i = |r: &Mat3, i: &Mat3| r * i * r.transpose();
        // e_k in P_k coordinates: the links P1, P2 carry the fixed rotation, P3..P5 do not.
        let e_p = |k: usize| -> Vec3 {
            if k < 2 {
                p.rotation[k].inverse_transform_vector(&p.e[k])
            } else {
                p.e[k]
            }
        };
        Self {
            m: p.mass,
            I: [
                p.inertia[0],
                rot_i(&t.o2, &p.inertia[1]),
                rot_i(&t.o3, &p.inertia[2]),
                rot_i(&t.o4, &p.inertia[3]),
            ],
            a1: p.a1,
            c2: t.o2 * p.c2,
            a2: t.o2 * p.a2,
            c3: t.o3 * p.c3,
            a3: t.o3 * p.a3,
            c4: t.o4 * p.c4,
            e: [
                t.p1 * e_p(0),
                t.p2 * e_p(1),
                t.p3 * e_p(2),
                t.p4 * e_p(3),
                t.p5 * e_p(4),
            ],
            omega1: s.omega1,
            psi: s.psi,
            M_u: s.m_u,
            M: [
                s.m_ext[0],
                t.o2 * s.m_ext[1],
                t.o3 * s.m_ext[2],
                t.o4 * s.m_ext[3],
            ],
        }
    }

    // ---- masses and relative vectors ----

    /// `m = m1 + m2 + m3 + m4`.
    pub fn m_total(&self) -> f64 {
        self.m.iter().sum()
    }
    fn mm(&self, i: usize, j: usize) -> f64 {
        self.m[i - 1] * self.m[j - 1] / self.m_total()
    }
    /// `m_{1,2} = m1 m2 / m`.
    pub fn m_12(&self) -> f64 {
        self.mm(1, 2)
    }
    /// `m_{1,3} = m1 m3 / m`.
    pub fn m_13(&self) -> f64 {
        self.mm(1, 3)
    }
    /// `m_{1,4} = m1 m4 / m`.
    pub fn m_14(&self) -> f64 {
        self.mm(1, 4)
    }
    /// `m_{2,3} = m2 m3 / m`.
    pub fn m_23(&self) -> f64 {
        self.mm(2, 3)
    }
    /// `m_{2,4} = m2 m4 / m`.
    pub fn m_24(&self) -> f64 {
        self.mm(2, 4)
    }
    /// `m_{3,4} = m3 m4 / m`.
    pub fn m_34(&self) -> f64 {
        self.mm(3, 4)
    }
    /// `d_{1,2} = a1 + c2`.
    pub fn d_12(&self) -> Vec3 {
        self.a1 + self.c2
    }
    /// `d_{1,3} = d_{1,2} + a2 + c3`.
    pub fn d_13(&self) -> Vec3 {
        self.d_12() + self.a2 + self.c3
    }
    /// `d_{1,4} = d_{1,3} + a3 + c4`.
    pub fn d_14(&self) -> Vec3 {
        self.d_13() + self.a3 + self.c4
    }
    /// `d_{2,3} = a2 + c3`.
    pub fn d_23(&self) -> Vec3 {
        self.a2 + self.c3
    }
    /// `d_{2,4} = d_{2,3} + a3 + c4`.
    pub fn d_24(&self) -> Vec3 {
        self.d_23() + self.a3 + self.c4
    }
    /// `d_{3,4} = a3 + c4`.
    pub fn d_34(&self) -> Vec3 {
        self.a3 + self.c4
    }

    // ---- the A matrices (brackets of S) ----

    /// `A_{1-3,4}`: the bracket of `S_{1-3,4}`.
    pub fn A_13_4(&self) -> Mat3 {
        let (c2, d23, d24, d34) = (self.c2, self.d_23(), self.d_24(), self.d_34());
        self.I[1]
            + self.I[2]
            + self.I[3]
            + self.m_12() * K(&self.d_12(), &c2)
            + self.m_13() * K(&self.d_13(), &(c2 + d23))
            + self.m_14() * K(&self.d_14(), &(c2 + d24))
            + self.m_23() * K(&d23, &d23)
            + self.m_24() * K(&d24, &d24)
            + self.m_34() * K(&d34, &d34)
    }
    /// `A_{1-3,7}`: the bracket of `S_{1-3,7}`.
    pub fn A_13_7(&self) -> Mat3 {
        let (c3, d34) = (self.c3, self.d_34());
        self.I[2]
            + self.I[3]
            + self.m_13() * K(&self.d_13(), &c3)
            + self.m_14() * K(&self.d_14(), &(c3 + d34))
            + self.m_23() * K(&self.d_23(), &c3)
            + self.m_24() * K(&self.d_24(), &(c3 + d34))
            + self.m_34() * K(&d34, &d34)
    }
    /// `A_{1-3,8}`: the bracket of `S_{1-3,8}`.
    pub fn A_13_8(&self) -> Mat3 {
        let c4 = self.c4;
        self.I[3]
            + self.m_14() * K(&self.d_14(), &c4)
            + self.m_24() * K(&self.d_24(), &c4)
            + self.m_34() * K(&self.d_34(), &c4)
    }
    /// `A_{4,4}`: the bracket of `S_{4,4}`.
    pub fn A_4_4(&self) -> Mat3 {
        let (c2, d23, d24, d34) = (self.c2, self.d_23(), self.d_24(), self.d_34());
        self.I[1]
            + self.I[2]
            + self.I[3]
            + self.m_12() * K(&c2, &c2)
            + self.m_13() * K(&(c2 + d23), &(c2 + d23))
            + self.m_14() * K(&(c2 + d24), &(c2 + d24))
            + self.m_23() * K(&d23, &d23)
            + self.m_24() * K(&d24, &d24)
            + self.m_34() * K(&d34, &d34)
    }
    /// `A_{4,7}`: the bracket of `S_{4,7}`.
    pub fn A_4_7(&self) -> Mat3 {
        let (c2, c3, d23, d24, d34) = (self.c2, self.c3, self.d_23(), self.d_24(), self.d_34());
        self.I[2]
            + self.I[3]
            + self.m_13() * K(&(c2 + d23), &c3)
            + self.m_14() * K(&(c2 + d24), &(c3 + d34))
            + self.m_23() * K(&d23, &c3)
            + self.m_24() * K(&d24, &(c3 + d34))
            + self.m_34() * K(&d34, &d34)
    }
    /// `A_{4,8}`: the bracket of `S_{4,8}`.
    pub fn A_4_8(&self) -> Mat3 {
        let (c2, c4, d24) = (self.c2, self.c4, self.d_24());
        self.I[3]
            + self.m_14() * K(&(c2 + d24), &c4)
            + self.m_24() * K(&d24, &c4)
            + self.m_34() * K(&self.d_34(), &c4)
    }
    /// The bracket of `S_{7,7}` (unnamed in the preprint).
    pub fn A_7_7(&self) -> Mat3 {
        let (c3, d34) = (self.c3, self.d_34());
        self.I[2]
            + self.I[3]
            + self.m_13() * K(&c3, &c3)
            + self.m_14() * K(&(c3 + d34), &(c3 + d34))
            + self.m_23() * K(&c3, &c3)
            + self.m_24() * K(&(c3 + d34), &(c3 + d34))
            + self.m_34() * K(&d34, &d34)
    }
    /// `A_{7,8}`: the bracket of `S_{7,8}`.
    pub fn A_7_8(&self) -> Mat3 {
        let (c3, c4, d34) = (self.c3, self.c4, self.d_34());
        self.I[3]
            + self.m_14() * K(&(c3 + d34), &c4)
            + self.m_24() * K(&(c3 + d34), &c4)
            + self.m_34() * K(&d34, &c4)
    }
    /// The bracket of `S_{8,8}` (unnamed in the preprint).
    pub fn A_8_8(&self) -> Mat3 {
        let c4 = self.c4;
        self.I[3]
            + self.m_14() * K(&c4, &c4)
            + self.m_24() * K(&c4, &c4)
            + self.m_34() * K(&c4, &c4)
    }

    // ---- the entries of S ----

    /// `S_{1-3,1-3} = I1 + I2 + I3 + I4 + Σ m_{i,j} K(d_{i,j}, d_{i,j})`.
    pub fn S_13_13(&self) -> Mat3 {
        let pairs = [
            (self.m_12(), self.d_12()),
            (self.m_13(), self.d_13()),
            (self.m_14(), self.d_14()),
            (self.m_23(), self.d_23()),
            (self.m_24(), self.d_24()),
            (self.m_34(), self.d_34()),
        ];
        pairs.iter().fold(
            self.I[0] + self.I[1] + self.I[2] + self.I[3],
            |s, (m, d)| s + *m * K(d, d),
        )
    }
    /// `S_{1-3,4} = A_{1-3,4} e1`.
    pub fn S_13_4(&self) -> Vec3 {
        self.A_13_4() * self.e[0]
    }
    /// `S_{1-3,5} = A_{1-3,4} e2`.
    pub fn S_13_5(&self) -> Vec3 {
        self.A_13_4() * self.e[1]
    }
    /// `S_{1-3,6} = A_{1-3,4} e3`.
    pub fn S_13_6(&self) -> Vec3 {
        self.A_13_4() * self.e[2]
    }
    /// `S_{1-3,7} = A_{1-3,7} e4` (corrected: the printed bracket lacks its `e4`, erratum E1).
    pub fn S_13_7(&self) -> Vec3 {
        self.A_13_7() * self.e[3]
    }
    /// `S_{1-3,7}` literally as printed: the bracket without `e4`, a 3x3 matrix where a
    /// column is needed (erratum E1).
    pub fn S_13_7_as_printed(&self) -> Mat3 {
        self.A_13_7()
    }
    /// `S_{1-3,8} = A_{1-3,8} e5`.
    pub fn S_13_8(&self) -> Vec3 {
        self.A_13_8() * self.e[4]
    }
    /// `S_{4,4} = e1ᵀ A_{4,4} e1`.
    pub fn S_4_4(&self) -> f64 {
        self.e[0].dot(&(self.A_4_4() * self.e[0]))
    }
    /// `S_{4,5} = e1ᵀ A_{4,4} e2`.
    pub fn S_4_5(&self) -> f64 {
        self.e[0].dot(&(self.A_4_4() * self.e[1]))
    }
    /// `S_{4,6} = e1ᵀ A_{4,4} e3`.
    pub fn S_4_6(&self) -> f64 {
        self.e[0].dot(&(self.A_4_4() * self.e[2]))
    }
    /// `S_{4,7} = e1ᵀ A_{4,7} e4`.
    pub fn S_4_7(&self) -> f64 {
        self.e[0].dot(&(self.A_4_7() * self.e[3]))
    }
    /// `S_{4,8} = e1ᵀ A_{4,8} e5`.
    pub fn S_4_8(&self) -> f64 {
        self.e[0].dot(&(self.A_4_8() * self.e[4]))
    }
    /// `S_{5,5} = e2ᵀ A_{4,4} e2`.
    pub fn S_5_5(&self) -> f64 {
        self.e[1].dot(&(self.A_4_4() * self.e[1]))
    }
    /// `S_{5,6} = e2ᵀ A_{4,4} e3`.
    pub fn S_5_6(&self) -> f64 {
        self.e[1].dot(&(self.A_4_4() * self.e[2]))
    }
    /// `S_{5,7} = e2ᵀ A_{4,7} e4`.
    pub fn S_5_7(&self) -> f64 {
        self.e[1].dot(&(self.A_4_7() * self.e[3]))
    }
    /// `S_{5,8} = e2ᵀ A_{4,8} e5`.
    pub fn S_5_8(&self) -> f64 {
        self.e[1].dot(&(self.A_4_8() * self.e[4]))
    }
    /// `S_{6,5} = e3ᵀ A_{4,4} e2` (printed explicitly, equal to `S_{5,6}`).
    pub fn S_6_5(&self) -> f64 {
        self.e[2].dot(&(self.A_4_4() * self.e[1]))
    }
    /// `S_{6,6} = e3ᵀ A_{4,4} e3`.
    pub fn S_6_6(&self) -> f64 {
        self.e[2].dot(&(self.A_4_4() * self.e[2]))
    }
    /// `S_{6,7} = e3ᵀ A_{4,7} e4`.
    pub fn S_6_7(&self) -> f64 {
        self.e[2].dot(&(self.A_4_7() * self.e[3]))
    }
    /// `S_{6,8} = e3ᵀ A_{4,8} e5`.
    pub fn S_6_8(&self) -> f64 {
        self.e[2].dot(&(self.A_4_8() * self.e[4]))
    }
    /// `S_{7,7} = e4ᵀ [I3 + I4 + m_{1,3} K(c3, c3) + …] e4`.
    pub fn S_7_7(&self) -> f64 {
        self.e[3].dot(&(self.A_7_7() * self.e[3]))
    }
    /// `S_{7,8} = e4ᵀ A_{7,8} e5`.
    pub fn S_7_8(&self) -> f64 {
        self.e[3].dot(&(self.A_7_8() * self.e[4]))
    }
    /// `S_{8,8} = e5ᵀ [I4 + (m_{1,4} + m_{2,4} + m_{3,4}) K(c4, c4)] e5`.
    pub fn S_8_8(&self) -> f64 {
        self.e[4].dot(&(self.A_8_8() * self.e[4]))
    }

    /// The 8x8 matrix `S` assembled as the preprint assembles it: the printed upper entries,
    /// `S_{6,5}` as printed, and the rest by the printed symmetry statements
    /// (`S_{5,4} = S_{4,5}`, `S_{4,1-3} = S_{1-3,4}ᵀ`, …). Only the corrected `S_{1-3,7}`
    /// can be assembled (the printed one is not a column).
    pub fn S(&self) -> SMatrix<f64, 8, 8> {
        let mut s = SMatrix::<f64, 8, 8>::zeros();
        s.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.S_13_13());
        let cols = [
            self.S_13_4(),
            self.S_13_5(),
            self.S_13_6(),
            self.S_13_7(),
            self.S_13_8(),
        ];
        for (k, c) in cols.iter().enumerate() {
            s.fixed_view_mut::<3, 1>(0, 3 + k).copy_from(c);
            s.fixed_view_mut::<1, 3>(3 + k, 0).copy_from(&c.transpose());
        }
        let upper = [
            (3, 3, self.S_4_4()),
            (3, 4, self.S_4_5()),
            (3, 5, self.S_4_6()),
            (3, 6, self.S_4_7()),
            (3, 7, self.S_4_8()),
            (4, 4, self.S_5_5()),
            (4, 5, self.S_5_6()),
            (4, 6, self.S_5_7()),
            (4, 7, self.S_5_8()),
            (5, 5, self.S_6_6()),
            (5, 6, self.S_6_7()),
            (5, 7, self.S_6_8()),
            (6, 6, self.S_7_7()),
            (6, 7, self.S_7_8()),
            (7, 7, self.S_8_8()),
        ];
        for (r, c, x) in upper {
            s[(r, c)] = x;
            s[(c, r)] = x;
        }
        s[(5, 4)] = self.S_6_5();
        s
    }

    // ---- velocities and velocity-product accelerations ----

    /// `ω1`.
    pub fn omega_1(&self) -> Vec3 {
        self.omega1
    }
    /// `ω2 = ω1 + e1ψ1 + e2ψ2 + e3ψ3` (11).
    pub fn omega_2(&self) -> Vec3 {
        self.omega1 + self.e[0] * self.psi[0] + self.e[1] * self.psi[1] + self.e[2] * self.psi[2]
    }
    /// `ω3 = ω2 + e4ψ4` (11).
    pub fn omega_3(&self) -> Vec3 {
        self.omega_2() + self.e[3] * self.psi[3]
    }
    /// `ω4 = ω3 + e5ψ5` (11).
    pub fn omega_4(&self) -> Vec3 {
        self.omega_3() + self.e[4] * self.psi[4]
    }
    fn omega(&self, i: usize) -> Vec3 {
        match i {
            1 => self.omega_1(),
            2 => self.omega_2(),
            3 => self.omega_3(),
            _ => self.omega_4(),
        }
    }
    /// `f2 = ω1×e1ψ1 + (ω1+e1ψ1)×e2ψ2 + (ω1+e1ψ1+e2ψ2)×e3ψ3`.
    pub fn f_2(&self) -> Vec3 {
        let (e, p, w1) = (&self.e, &self.psi, self.omega1);
        w1.cross(&(e[0] * p[0]))
            + (w1 + e[0] * p[0]).cross(&(e[1] * p[1]))
            + (w1 + e[0] * p[0] + e[1] * p[1]).cross(&(e[2] * p[2]))
    }
    /// `f3 = f2 + ω2×e4ψ4`.
    pub fn f_3(&self) -> Vec3 {
        self.f_2() + self.omega_2().cross(&(self.e[3] * self.psi[3]))
    }
    /// `f4 = f3 + ω3×e5ψ5`.
    pub fn f_4(&self) -> Vec3 {
        self.f_3() + self.omega_3().cross(&(self.e[4] * self.psi[4]))
    }
    fn f(&self, i: usize) -> Vec3 {
        match i {
            2 => self.f_2(),
            3 => self.f_3(),
            4 => self.f_4(),
            _ => Vec3::zeros(),
        }
    }
    /// `g1 = ω1×ω1×a1`, read `ω1×(ω1×a1)`.
    pub fn g_1(&self) -> Vec3 {
        let w = self.omega1;
        w.cross(&w.cross(&self.a1))
    }
    /// `g2 = f2×a2 + ω2×ω2×a2`.
    pub fn g_2(&self) -> Vec3 {
        let w = self.omega_2();
        self.f_2().cross(&self.a2) + w.cross(&w.cross(&self.a2))
    }
    /// `g3 = f3×a3 + ω3×ω3×a3`.
    pub fn g_3(&self) -> Vec3 {
        let w = self.omega_3();
        self.f_3().cross(&self.a3) + w.cross(&w.cross(&self.a3))
    }
    /// `h2 = f2×c2 + ω2×ω2×c2`.
    pub fn h_2(&self) -> Vec3 {
        let w = self.omega_2();
        self.f_2().cross(&self.c2) + w.cross(&w.cross(&self.c2))
    }
    /// `h3 = f3×c3 + ω3×ω3×c3`.
    pub fn h_3(&self) -> Vec3 {
        let w = self.omega_3();
        self.f_3().cross(&self.c3) + w.cross(&w.cross(&self.c3))
    }
    /// `h4 = f4×c4 + ω4×ω4×c4`.
    pub fn h_4(&self) -> Vec3 {
        let w = self.omega_4();
        self.f_4().cross(&self.c4) + w.cross(&w.cross(&self.c4))
    }
    /// `j_{1,2} = g1 + h2`.
    pub fn j_12(&self) -> Vec3 {
        self.g_1() + self.h_2()
    }
    /// `j_{1,3} = j_{1,2} + g2 + h3`.
    pub fn j_13(&self) -> Vec3 {
        self.j_12() + self.g_2() + self.h_3()
    }
    /// `j_{1,4} = j_{1,3} + g3 + h4`.
    pub fn j_14(&self) -> Vec3 {
        self.j_13() + self.g_3() + self.h_4()
    }
    /// `j_{2,3} = g2 + h3`.
    pub fn j_23(&self) -> Vec3 {
        self.g_2() + self.h_3()
    }
    /// `j_{2,4} = j_{2,3} + g3 + h4`.
    pub fn j_24(&self) -> Vec3 {
        self.j_23() + self.g_3() + self.h_4()
    }
    /// `j_{3,4} = g3 + h4`.
    pub fn j_34(&self) -> Vec3 {
        self.g_3() + self.h_4()
    }

    /// `M_i − ω_i × I_i ω_i − I_i f_i` for body `i` (with `f1 = 0`).
    fn body_term(&self, i: usize) -> Vec3 {
        let w = self.omega(i);
        let ii = &self.I[i - 1];
        self.M[i - 1] - w.cross(&(ii * w)) - ii * self.f(i)
    }

    // ---- the right-hand side N ----

    /// `N1`. Corrected: `Σ_{i=1}^4 (M_i − ω_i×I_iω_i) − I2f2 − I3f3 − I4f4 − Σ m_{i,j}
    /// d_{i,j}×j_{i,j}`. As printed the sum has no parentheses, so it covers `M_i` only and
    /// leaves a dangling `ω_i×I_iω_i`, read here as the bus's `ω1×I1ω1` (erratum E2).
    pub fn N1(&self, variant: Variant) -> Vec3 {
        let gyro = match variant {
            Variant::Corrected => (1..=4)
                .map(|i| {
                    let w = self.omega(i);
                    w.cross(&(self.I[i - 1] * w))
                })
                .sum::<Vec3>(),
            Variant::Printed => self.omega1.cross(&(self.I[0] * self.omega1)),
        };
        self.M.iter().sum::<Vec3>()
            - gyro
            - self.I[1] * self.f_2()
            - self.I[2] * self.f_3()
            - self.I[3] * self.f_4()
            - self.m_12() * self.d_12().cross(&self.j_12())
            - self.m_13() * self.d_13().cross(&self.j_13())
            - self.m_14() * self.d_14().cross(&self.j_14())
            - self.m_23() * self.d_23().cross(&self.j_23())
            - self.m_24() * self.d_24().cross(&self.j_24())
            - self.m_34() * self.d_34().cross(&self.j_34())
    }
    /// The bracket shared by `n1, n2, n3`.
    fn gimbal_bracket(&self) -> Vec3 {
        let (c2, d23, d24) = (self.c2, self.d_23(), self.d_24());
        (2..=4).map(|i| self.body_term(i)).sum::<Vec3>()
            - self.m_12() * c2.cross(&self.j_12())
            - self.m_13() * (c2 + d23).cross(&self.j_13())
            - self.m_14() * (c2 + d24).cross(&self.j_14())
            - self.m_23() * d23.cross(&self.j_23())
            - self.m_24() * d24.cross(&self.j_24())
            - self.m_34() * self.d_34().cross(&self.j_34())
    }
    /// `n1 = M_u1 + e1ᵀ[Σ_{i=2}^4 (M_i − ω_i×I_iω_i − I_if_i) − m_{1,2} c2×j_{1,2} − …]`.
    pub fn n_1(&self) -> f64 {
        self.M_u[0] + self.e[0].dot(&self.gimbal_bracket())
    }
    /// `n2`: as `n1` with `M_u2`, `e2`.
    pub fn n_2(&self) -> f64 {
        self.M_u[1] + self.e[1].dot(&self.gimbal_bracket())
    }
    /// `n3`: as `n1` with `M_u3`, `e3`.
    pub fn n_3(&self) -> f64 {
        self.M_u[2] + self.e[2].dot(&self.gimbal_bracket())
    }
    /// `n4 = M_u4 + e4ᵀ[Σ_{i=3}^4 (…) − m_{1,3} c3×j_{1,3} − m_{1,4}(c3+d_{3,4})×j_{1,4}
    /// − m_{2,3} c3×j_{2,3} − m_{2,4}(c3+d_{3,4})×j_{2,4} − m_{3,4} d_{3,4}×j_{3,4}]`.
    /// Printed with `(c3 + d_{2,4})` in the `m_{2,4}` term (erratum E3).
    pub fn n_4(&self, variant: Variant) -> f64 {
        let (c3, d34) = (self.c3, self.d_34());
        let arm_24 = match variant {
            Variant::Printed => c3 + self.d_24(),
            Variant::Corrected => c3 + d34,
        };
        let bracket = self.body_term(3) + self.body_term(4)
            - self.m_13() * c3.cross(&self.j_13())
            - self.m_14() * (c3 + d34).cross(&self.j_14())
            - self.m_23() * c3.cross(&self.j_23())
            - self.m_24() * arm_24.cross(&self.j_24())
            - self.m_34() * d34.cross(&self.j_34());
        self.M_u[3] + self.e[3].dot(&bracket)
    }
    /// `n5 = M_u5 + e5ᵀ[M4 − ω4×I4ω4 − I4f4 − m_{1,4} c4×j_{1,4} − m_{2,4} c4×j_{2,4} −
    /// m_{3,4} c4×j_{3,4}]`.
    pub fn n_5(&self) -> f64 {
        let c4 = self.c4;
        let bracket = self.body_term(4)
            - self.m_14() * c4.cross(&self.j_14())
            - self.m_24() * c4.cross(&self.j_24())
            - self.m_34() * c4.cross(&self.j_34());
        self.M_u[4] + self.e[4].dot(&bracket)
    }
    /// `N2 = (n1, n2, n3, n4, n5)ᵀ`.
    pub fn N2(&self, variant: Variant) -> SVector<f64, 5> {
        SVector::<f64, 5>::new(
            self.n_1(),
            self.n_2(),
            self.n_3(),
            self.n_4(variant),
            self.n_5(),
        )
    }
    /// `N = (N1, N2)`.
    pub fn N(&self, variant: Variant) -> SVector<f64, 8> {
        let mut n = SVector::<f64, 8>::zeros();
        n.fixed_rows_mut::<3>(0).copy_from(&self.N1(variant));
        n.fixed_rows_mut::<5>(3).copy_from(&self.N2(variant));
        n
    }
}
