/* The kinetic single-track multibody model (seed 000, section II): generic
 * Jacobians of the points of a chain of n modules, the mass matrix M(z), the
 * velocity term G(z, z') z', the generalised forces of the tyres (eqs. 5-14)
 * and of the hinge torques, and the tyre models (section II-B).
 * Every matrix has its size fixed at compile time (the module count is a
 * template parameter, 1..4 instantiated): no heap allocation in the
 * right-hand side, and Eigen unrolls the small products. */
#include <cmath>

/* Eigen's small fixed-size expressions inlined whole: on the vector dual type
   (dyn_eval_jacobian) GCC otherwise calls every scalar operation of a product
   as a function (3x slower); on double it changes no result (no reordering,
   no contraction: strict IEEE arithmetic either way). Only where the compiler
   optimises: in a debug build forced inlining costs compile time for nothing */
#if defined(__GNUC__) && defined(__OPTIMIZE__) && !defined(EIGEN_STRONG_INLINE)
#define EIGEN_STRONG_INLINE inline __attribute__((always_inline))
#endif
#include <Eigen/Dense>

#include "dual.hpp"
#include "dynamics.h"

/* The equations are templated on the scalar type T as well: double for the
 * simulation, artibus::Dual (src/models/common/dual.hpp) for a directional
 * derivative (dyn_eval_tangent) and artibus::DualN<2 nq - 2> for the Jacobian
 * of the equations of motion by every state at once (dyn_eval_jacobian): forward-mode differentiation
 * through the one source of the equations. Eigen takes them as custom scalars. */
namespace Eigen {
template <int K> struct NumTraits<artibus::DualN<K>> : NumTraits<double> {
    typedef artibus::DualN<K> Real;
    typedef artibus::DualN<K> NonInteger;
    typedef artibus::DualN<K> Nested;
    typedef artibus::DualN<K> Literal;
    enum { IsComplex = 0, IsInteger = 0, IsSigned = 1, RequireInitialization = 1,
           ReadCost = 2, AddCost = 2, MulCost = 4 };   /* as double: Eigen unrolls the small products */
};
template <int K, typename BinOp> struct ScalarBinaryOpTraits<artibus::DualN<K>, double, BinOp> {
    typedef artibus::DualN<K> ReturnType;
};
template <int K, typename BinOp> struct ScalarBinaryOpTraits<double, artibus::DualN<K>, BinOp> {
    typedef artibus::DualN<K> ReturnType;
};
}  // namespace Eigen

namespace {

using artibus::Dual;
template <class T> using Vec2T = Eigen::Matrix<T, 2, 1>;
using Vec2 = Vec2T<double>;

/* the inputs and outputs on T: for double the C structs of dynamics.h, for
   a dual type the same fields on it */
template <class S> struct DualInputs {
    S Fx[DYN_MAX_AXLES + 1], Mjoint[DYN_MAX_HINGES + 1];
    S cosDelta[DYN_MAX_AXLES + 1], sinDelta[DYN_MAX_AXLES + 1];
};
template <class S> struct DualOut {
    S zdd[DYN_MAX_Q];
    S xCG[DYN_MAX_MODULES + 1], yCG[DYN_MAX_MODULES + 1];
    S vx[DYN_MAX_MODULES + 1], vy[DYN_MAX_MODULES + 1];
    S ax[DYN_MAX_MODULES + 1], ay[DYN_MAX_MODULES + 1];
    S xAxle[DYN_MAX_AXLES + 1], yAxle[DYN_MAX_AXLES + 1];
    S alpha[DYN_MAX_AXLES + 1], Fy[DYN_MAX_AXLES + 1];
    S FjX[DYN_MAX_HINGES + 1], FjY[DYN_MAX_HINGES + 1];
    S xCorner[4 * DYN_MAX_MODULES + 1], yCorner[4 * DYN_MAX_MODULES + 1];
    S v;
};
template <class T> struct Types { using In = DualInputs<T>; using Out = DualOut<T>; };
template <> struct Types<double> { using In = DynInputs; using Out = DynOut; };

/* A point xi ahead of the CG of module m is
 *     r = (x, y) + sum_{j=1..m} l_j e(psi_j)
 * where l_j is the lever of module j along the chain: from where the chain
 * enters module j (its CG for j = 1, its front hinge for j > 1) to where it
 * leaves it (its rear hinge, j < m) or to the point (j = m). */
void levers(const DynParams *p, int m, double xi, double *l) {
    for (int j = 1; j <= m; j++) {
        const double entry = j == 1 ? 0.0 : p->lHr[j - 1];
        l[j] = (j < m ? -p->lHf[j] : xi) - entry;
    }
}

/* cos and sin of the yaw angle of each of N modules, computed once per evaluation */
template <int N, class T>
struct Trig {
    T c[N + 1], s[N + 1];
    explicit Trig(const T *z) {
        using std::cos;
        using std::sin;
        for (int m = 1; m <= N; m++) { c[m] = cos(z[1 + m]); s[m] = sin(z[1 + m]); }
    }
    Vec2T<T> e(int m) const { return Vec2T<T>(c[m], s[m]); }     /* module x axis */
    Vec2T<T> n(int m) const { return Vec2T<T>(-s[m], c[m]); }    /* module y axis */
    Eigen::Matrix<T, 2, 2> A(int m) const {                     /* A_IK of eq. 6 */
        Eigen::Matrix<T, 2, 2> R;
        R << c[m], -s[m], s[m], c[m];
        return R;
    }
};

/* M x = b for the symmetric positive definite mass matrix: Cholesky (false if
   M is not positive definite). On Dual: the values by Cholesky, the
   derivatives from M dx = db - dM x with the same factor */
template <int NQ>
bool solve_spd(const Eigen::Matrix<double, NQ, NQ> &M, const Eigen::Matrix<double, NQ, 1> &b,
               Eigen::Matrix<double, NQ, 1> &x) {
    Eigen::LLT<Eigen::Matrix<double, NQ, NQ>> llt(M);
    if (llt.info() != Eigen::Success) return false;
    x = llt.solve(b);
    return true;
}

template <int NQ, int K>
bool solve_spd(const Eigen::Matrix<artibus::DualN<K>, NQ, NQ> &M, const Eigen::Matrix<artibus::DualN<K>, NQ, 1> &b,
               Eigen::Matrix<artibus::DualN<K>, NQ, 1> &x) {
    using D = artibus::DualN<K>;
    const Eigen::Matrix<double, NQ, NQ> M0 = M.unaryExpr([](const D &a) { return a.v; });
    Eigen::LLT<Eigen::Matrix<double, NQ, NQ>> llt(M0);
    if (llt.info() != Eigen::Success) return false;
    const Eigen::Matrix<double, NQ, 1> x0 = llt.solve(b.unaryExpr([](const D &a) { return a.v; }));
    for (int i = 0; i < NQ; i++) x(i) = D(x0(i));
    for (int k = 0; k < K; k++) {           /* seed k: M dx = db - dM x */
        const auto dk = [k](const D &a) { return a.d[k]; };
        const Eigen::Matrix<double, NQ, 1> dx = llt.solve(b.unaryExpr(dk) - M.unaryExpr(dk) * x0);
        for (int i = 0; i < NQ; i++) x(i).d[k] = dx(i);
    }
    return true;
}

template <class T>
T slip(T u, T w, double vSlip) {
    /* eqs. 25, 26: alpha = gamma - arctan(vy/vx) is the angle from the velocity
     * of the axle to its wheel plane, i.e. atan2(-w, u) for the velocity (u, w)
     * in wheel coordinates. |u| keeps the force opposed to the lateral sliding
     * when reversing; vSlip keeps it finite at standstill: below about vSlip the
     * tyre acts as a lateral damper C / vSlip instead of dividing by zero. At
     * u = 1 m/s and vSlip = 0.01 m/s the slip is scaled by 1 - 5e-5. The
     * second argument is > 0, so atan2 is the plain arctangent of the ratio
     * (cheaper: it is evaluated for every axle in every right-hand side). */
    using std::atan;
    using std::sqrt;
    return atan(-w / sqrt(u * u + vSlip * vSlip));
}

template <class T>
T tyre(const DynParams *p, int a, T alpha) {
    using std::fabs;
    using std::tan;
    const double C = p->C[a], mu = p->mu[a], Fz = p->Fz[a];
    switch (p->tyreModel) {
    case TYRE_LINEAR_FRICTION: {
        /* seed 001: friction scales the cornering stiffness (C_eff = mu C), and
           the force cannot exceed what the friction carries */
        const T F = mu * C * alpha;
        const double Fmax = mu * Fz;
        return F > Fmax ? T(Fmax) : (F < -Fmax ? T(-Fmax) : F);
    }
    case TYRE_FIALA: {
        /* brush model (Fiala 1954; Pacejka, Tyre and Vehicle Dynamics, 2012,
           sec. 3.2): cubic in tan(alpha) up to full sliding at
           tan(alpha_sl) = 3 mu Fz / C, then mu Fz; slope C at alpha = 0 */
        const double Fmax = mu * Fz;
        if (!(Fmax > 0.0) || !(C > 0.0)) return T(0.0);
        const T t = tan(alpha);
        const double tsl = 3.0 * Fmax / C;
        if (fabs(t) >= tsl) return T(t > 0 ? Fmax : -Fmax);
        const T s = t / tsl;   /* -1 .. 1 */
        return Fmax * (3.0 * s - 3.0 * s * fabs(s) + s * s * s);
    }
    case TYRE_LINEAR_SCALED:
        /* seed 001, 3.1 and eq. C.1: the extensive model's linear tyre, its
           friction coefficient scaling the tyre coefficient, nothing saturates */
        return mu * C * alpha;
    default:
        return C * alpha;          /* eq. 24 */
    }
}

/* The chain of N modules (N + 2 minimal coordinates). The module count is a
 * template parameter so that every matrix has a size known to the compiler
 * (Eigen then unrolls the small products); dyn_eval picks N at run time. */
template <int N, class S = double>
struct Chain {
    static constexpr int NQ = 2 + N;
    using VecQ = Eigen::Matrix<S, NQ, 1>;
    using MatQ = Eigen::Matrix<S, NQ, NQ>;
    using Jac = Eigen::Matrix<S, 2, NQ>;
    using Vec2 = Vec2T<S>;
    using In = typename Types<S>::In;
    using Out = typename Types<S>::Out;

    /* position r, velocity v, Jacobian J = dr/dz (eq. 7) and the
       velocity-product term J' z' */
    struct Point {
        Vec2 r, v, Jdzd;
        Jac J;
    };

    static Point point(const DynParams *p, const Trig<N, S> &T, const S *z, const S *zd,
                       int m, double xi) {
        double l[DYN_MAX_MODULES + 1];
        levers(p, m, xi, l);
        Point P;
        P.J.setZero();
        P.J(0, 0) = 1.0;
        P.J(1, 1) = 1.0;
        P.r = Vec2(z[0], z[1]);
        P.Jdzd.setZero();
        for (int j = 1; j <= m; j++) {
            const S r = zd ? zd[1 + j] : S(0.0);
            P.r += l[j] * T.e(j);
            P.J.col(1 + j) = l[j] * T.n(j);              /* d(l e(psi))/dpsi = l n(psi) */
            P.Jdzd -= l[j] * r * r * T.e(j);             /* d(l n(psi))/dt psi' = -l e(psi) psi'^2 */
        }
        if (zd) P.v = P.J * Eigen::Map<const VecQ>(zd);
        return P;
    }

    static Vec2 position(const DynParams *p, const S *z, int m, double xi) {
        return point(p, Trig<N, S>(z), z, nullptr, m, xi).r;
    }

    static int eval(const DynParams *p, const In *u, const S *z, const S *zd, S *zdd, Out *out);
};
}  // namespace

extern "C" double dyn_slip(double u, double w, double vSlip) {
    return slip(u, w, vSlip);
}

extern "C" void dyn_steer(DynInputs *u, int nAxle) {
    for (int a = 1; a <= nAxle; a++) {
        u->cosDelta[a] = std::cos(u->delta[a]);
        u->sinDelta[a] = std::sin(u->delta[a]);
    }
}

extern "C" double dyn_tyre(const DynParams *p, int a, double alpha) {
    return tyre(p, a, alpha);
}

extern "C" void dyn_point(const DynParams *p, const double *z, int m, double xi,
                          double *px, double *py) {
    Vec2 r;
    switch (p->nMod) {
    case 1: r = Chain<1>::position(p, z, m, xi); break;
    case 2: r = Chain<2>::position(p, z, m, xi); break;
    case 3: r = Chain<3>::position(p, z, m, xi); break;
    default: r = Chain<4>::position(p, z, m, xi); break;
    }
    *px = r.x();
    *py = r.y();
}

template <int N, class S>
int Chain<N, S>::eval(const DynParams *p, const In *u, const S *z, const S *zd, S *zdd, Out *out) {
    constexpr int nq = NQ;
    const Trig<N, S> T(z);
    MatQ M = MatQ::Zero();
    VecQ h = VecQ::Zero(), q = VecQ::Zero();
    Point Cg[N + 1];                        /* the CG of each module */
    Vec2 vCgK[N + 1];                       /* its velocity in K_m */
    Vec2 Fw[DYN_MAX_AXLES + 1];             /* tyre force of each axle, world frame */

    /* mass matrix and velocity term, module by module (eq. 3) */
    for (int m = 1; m <= N; m++) {
        const Point &C = Cg[m] = point(p, T, z, zd, m, 0.0);
        M.noalias() += p->m[m] * C.J.transpose() * C.J;
        M(1 + m, 1 + m) += p->J[m];
        h.noalias() += p->m[m] * C.J.transpose() * C.Jdzd;
        vCgK[m] = T.A(m).transpose() * C.v;
        if (out) {
            out->xCG[m] = C.r.x();
            out->yCG[m] = C.r.y();
            out->vx[m] = vCgK[m].x();
            out->vy[m] = vCgK[m].y();
        }
    }

    /* tyre forces (eqs. 22-28) and their generalised forces (eqs. 5-9). Axle a
       lies xi ahead of the CG of its module m: r_a = r_CG + xi e(psi_m), so
       J_a = J_CG + xi n(psi_m) (in column psi_m) and, in K_m, its velocity is
       the CG's plus xi psi_m' across (eq. 27) */
    for (int a = 1; a <= p->nAxle; a++) {
        const int m = p->axleModule[a];
        const double xi = p->xA[a];
        const Vec2 vK(vCgK[m].x(), vCgK[m].y() + xi * zd[1 + m]);   /* eq. 27 */
        const S cd = u->cosDelta[a], sd = u->sinDelta[a];
        const S uw = cd * vK.x() + sd * vK.y();                /* eq. 23 applied to the velocity */
        const S ww = -sd * vK.x() + cd * vK.y();
        const S alpha = slip(uw, ww, p->vSlip);
        const S Fy = tyre(p, a, alpha);
        const Vec2 fA(u->Fx[a], Fy);                             /* wheel frame A_i */
        const Vec2 fK(cd * fA.x() - sd * fA.y(), sd * fA.x() + cd * fA.y());   /* eq. 28: A_KA f */
        Fw[a] = T.A(m) * fK;
        /* eq. 8: J_a^T F = J_CG^T F + xi (n(psi_m) . F) in row psi_m, and
           n(psi_m) . A_IK fK is fK's lateral component */
        q.noalias() += Cg[m].J.transpose() * Fw[a];
        q(1 + m) += xi * fK.y();
        if (out) {
            const Vec2 r = Cg[m].r + xi * T.e(m);
            out->xAxle[a] = r.x();
            out->yAxle[a] = r.y();
            out->alpha[a] = alpha;
            out->Fy[a] = Fy;
        }
    }
    /* hinge torques: +Mjoint on the rear module k+1, -Mjoint on the front one k */
    for (int k = 1; k < N; k++) {
        q(2 + k) += u->Mjoint[k];
        q(1 + k) -= u->Mjoint[k];
    }

    VecQ acc;
    if (!solve_spd(M, VecQ(q - h), acc)) return 1;
    for (int i = 0; i < nq; i++) zdd[i] = acc(i);

    if (out) {
        for (int i = 0; i < nq; i++) out->zdd[i] = acc(i);
        Vec2 aCG[DYN_MAX_MODULES + 1];
        for (int m = 1; m <= N; m++) {
            aCG[m] = Cg[m].J * acc + Cg[m].Jdzd;
            const Vec2 aK = T.A(m).transpose() * aCG[m];
            out->ax[m] = aK.x();
            out->ay[m] = aK.y();
        }
        /* hinge k: Newton's law for the rear part, modules k+1..n: the force
           the front module exerts on it is its mass times acceleration minus
           its tyre forces; expressed in the front module's frame K_k */
        for (int k = 1; k < N; k++) {
            Vec2 F = Vec2::Zero();
            for (int m = k + 1; m <= N; m++) F += p->m[m] * aCG[m];
            for (int a = 1; a <= p->nAxle; a++)
                if (p->axleModule[a] > k) F -= Fw[a];
            const Vec2 FK = T.A(k).transpose() * F;
            out->FjX[k] = FK.x();
            out->FjY[k] = FK.y();
        }
        /* body outline: front left, front right, rear right, rear left */
        for (int m = 1; m <= N; m++) {
            const double lon[4] = { p->lFront[m], p->lFront[m], -p->lRear[m], -p->lRear[m] };
            const double lat[4] = { 0.5, -0.5, -0.5, 0.5 };
            for (int c = 0; c < 4; c++) {
                const int i = 4 * (m - 1) + c + 1;
                const double w = lat[c] * p->width[m];
                out->xCorner[i] = out->xCG[m] + lon[c] * T.c[m] - w * T.s[m];
                out->yCorner[i] = out->yCG[m] + lon[c] * T.s[m] + w * T.c[m];
            }
        }
        using std::hypot;
        out->v = hypot(zd[0], zd[1]);
    }
    return 0;
}

template <class S>
int eval_n(const DynParams *p, const typename Types<S>::In *u, const S *z, const S *zd, S *zdd,
           typename Types<S>::Out *out) {
    switch (p->nMod) {
    case 1: return Chain<1, S>::eval(p, u, z, zd, zdd, out);
    case 2: return Chain<2, S>::eval(p, u, z, zd, zdd, out);
    case 3: return Chain<3, S>::eval(p, u, z, zd, zdd, out);
    case 4: return Chain<4, S>::eval(p, u, z, zd, zdd, out);
    default: return 1;   /* nModules is checked against 1..DYN_MAX_MODULES before */
    }
}

extern "C" int dyn_eval(const DynParams *p, const DynInputs *u, const double *z,
                        const double *zd, double *zdd, DynOut *out) {
    return eval_n<double>(p, u, z, zd, zdd, out);
}

/* the same equations on dual numbers: the values into out (zdd), their
   derivatives along (du, dz, dzd) into dout (dzdd) */
extern "C" int dyn_eval_tangent(const DynParams *p, const DynInputs *u, const DynInputs *du,
                                const double *z, const double *dz, const double *zd, const double *dzd,
                                double *zdd, double *dzdd, DynOut *out, DynOut *dout) {
    DualInputs<Dual> ui;
    for (int a = 1; a <= DYN_MAX_AXLES; a++) {
        const Dual delta(u->delta[a], du->delta[a]);
        ui.cosDelta[a] = cos(delta);
        ui.sinDelta[a] = sin(delta);
        ui.Fx[a] = Dual(u->Fx[a], du->Fx[a]);
    }
    for (int k = 1; k <= DYN_MAX_HINGES; k++) ui.Mjoint[k] = Dual(u->Mjoint[k], du->Mjoint[k]);
    Dual zz[DYN_MAX_Q], zzd[DYN_MAX_Q], zzdd[DYN_MAX_Q];
    for (int i = 0; i < DYN_MAX_Q; i++) {
        zz[i] = Dual(z[i], dz[i]);
        zzd[i] = Dual(zd[i], dzd[i]);
    }
    DualOut<Dual> o;
    if (eval_n<Dual>(p, &ui, zz, zzd, zzdd, &o)) return 1;
    const int nq = dyn_nq(p);
    for (int i = 0; i < nq; i++) { zdd[i] = zzdd[i].v; dzdd[i] = zzdd[i].d[0]; }
    /* every field of DynOut is a double array or a double: split each pair */
    const Dual *src = reinterpret_cast<const Dual *>(&o);
    double *val = reinterpret_cast<double *>(out), *der = reinterpret_cast<double *>(dout);
    static_assert(sizeof(DualOut<Dual>) == 2 * sizeof(DynOut), "DualOut mirrors DynOut");
    for (size_t i = 0; i < sizeof(DynOut) / sizeof(double); i++) {
        val[i] = src[i].v;
        der[i] = src[i].d[0];
    }
    return 0;
}

/* vector mode for N modules: the seeds of the states at once, seed k the unit
   vector of psi_(k+1) (z[k + 2], k < N) or of zd[k - N]; the inputs held. x and
   y (z[0], z[1]) are not seeded: the equations of motion do not depend on where
   the bus is (eq. 3: M, G z' and the tyre forces are functions of the yaw angles
   and the velocities alone; x and y enter the positions only, outputs not
   computed here), so their columns of zdd are 0. */
template <int N>
int eval_jacobian(const DynParams *p, const DynInputs *u, const double *z, const double *zd,
                  double *zdd, double (*dzdd)[DYN_MAX_Q]) {
    constexpr int NQ = 2 + N, K = 2 * NQ - 2;   /* seed k: state k + 2 of [z, zd] */
    using D = artibus::DualN<K>;
    DualInputs<D> ui;
    for (int a = 1; a <= DYN_MAX_AXLES; a++) {
        ui.cosDelta[a] = D(u->cosDelta[a]);
        ui.sinDelta[a] = D(u->sinDelta[a]);
        ui.Fx[a] = D(u->Fx[a]);
    }
    for (int k = 1; k <= DYN_MAX_HINGES; k++) ui.Mjoint[k] = D(u->Mjoint[k]);
    D zz[DYN_MAX_Q], zzd[DYN_MAX_Q], zzdd[DYN_MAX_Q];
    for (int i = 0; i < DYN_MAX_Q; i++) {
        zz[i] = D(z[i]);
        zzd[i] = D(zd[i]);
        if (i < NQ) {
            if (i >= 2) zz[i].d[i - 2] = 1.0;
            zzd[i].d[NQ + i - 2] = 1.0;
        }
    }
    if (Chain<N, D>::eval(p, &ui, zz, zzd, zzdd, nullptr)) return 1;
    for (int i = 0; i < NQ; i++) {
        zdd[i] = zzdd[i].v;
        dzdd[0][i] = dzdd[1][i] = 0.0;
        for (int k = 0; k < K; k++) dzdd[k + 2][i] = zzdd[i].d[k];
    }
    return 0;
}

extern "C" int dyn_eval_jacobian(const DynParams *p, const DynInputs *u, const double *z, const double *zd,
                                 double *zdd, double (*dzdd)[DYN_MAX_Q]) {
    switch (p->nMod) {
    case 1: return eval_jacobian<1>(p, u, z, zd, zdd, dzdd);
    case 2: return eval_jacobian<2>(p, u, z, zd, zdd, dzdd);
    case 3: return eval_jacobian<3>(p, u, z, zd, zdd, dzdd);
    case 4: return eval_jacobian<4>(p, u, z, zd, zdd, dzdd);
    default: return 1;
    }
}

extern "C" int dyn_static_loads(DynParams *p, double g) {
    double Vdown = 0.0;   /* vertical load the rear hinge puts on the current module */
    for (int m = p->nMod; m >= 1; m--) {
        double x[DYN_MAX_AXLES + 1];
        int idx[DYN_MAX_AXLES + 1], U = 0;
        for (int a = 1; a <= p->nAxle; a++)
            if (p->axleModule[a] == m) { idx[U] = a; x[U] = p->xA[a]; U++; }
        const int nAxOnModule = U;
        const bool hingeCarries = m >= 2 && nAxOnModule < 2;
        if (hingeCarries) { idx[U] = 0; x[U] = p->lHr[m - 1]; U++; }
        if (U < 2) return m;
        /* A F = b with A = [1 ... 1; x_1 ... x_U], b = [W; M] */
        const double W = p->m[m] * g + Vdown;
        const double Mo = m < p->nMod ? -p->lHf[m] * Vdown : 0.0;
        double s0 = U, s1 = 0.0, s2 = 0.0;
        for (int i = 0; i < U; i++) { s1 += x[i]; s2 += x[i] * x[i]; }
        const double det = s0 * s2 - s1 * s1;              /* A A^T = [s0 s1; s1 s2] */
        if (!(det > 1e-12 * (1.0 + s2) * s0)) return m;
        const double l0 = (s2 * W - s1 * Mo) / det, l1 = (s0 * Mo - s1 * W) / det;
        Vdown = 0.0;
        for (int i = 0; i < U; i++) {
            const double F = l0 + l1 * x[i];              /* F = A^T (A A^T)^-1 b */
            if (F < 0.0) return m;
            if (idx[i]) p->Fz[idx[i]] = F;
            else Vdown = F;                               /* passed on to module m-1 */
        }
    }
    return 0;
}
