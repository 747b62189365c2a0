/* The kinetic single-track multibody model (seed 000, section II): generic
 * Jacobians of the points of a chain of n modules, the mass matrix M(z), the
 * velocity term G(z, z') z', the generalised forces of the tyres (eqs. 5-14)
 * and of the hinge torques, and the tyre models (section II-B).
 * Every matrix has its size fixed at compile time (the module count is a
 * template parameter, 1..4 instantiated): no heap allocation in the
 * right-hand side, and Eigen unrolls the small products. */
#include <cmath>

#include <Eigen/Dense>

#include "dynamics.h"

namespace {

using Vec2 = Eigen::Vector2d;

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
template <int N>
struct Trig {
    double c[N + 1], s[N + 1];
    explicit Trig(const double *z) {
        for (int m = 1; m <= N; m++) { c[m] = std::cos(z[1 + m]); s[m] = std::sin(z[1 + m]); }
    }
    Vec2 e(int m) const { return Vec2(c[m], s[m]); }     /* module x axis */
    Vec2 n(int m) const { return Vec2(-s[m], c[m]); }    /* module y axis */
    Eigen::Matrix2d A(int m) const {                     /* A_IK of eq. 6 */
        Eigen::Matrix2d R;
        R << c[m], -s[m], s[m], c[m];
        return R;
    }
};

/* The chain of N modules (N + 2 minimal coordinates). The module count is a
 * template parameter so that every matrix has a size known to the compiler
 * (Eigen then unrolls the small products); dyn_eval picks N at run time. */
template <int N>
struct Chain {
    static constexpr int NQ = 2 + N;
    using VecQ = Eigen::Matrix<double, NQ, 1>;
    using MatQ = Eigen::Matrix<double, NQ, NQ>;
    using Jac = Eigen::Matrix<double, 2, NQ>;

    /* position r, velocity v, Jacobian J = dr/dz (eq. 7) and the
       velocity-product term J' z' */
    struct Point {
        Vec2 r, v, Jdzd;
        Jac J;
    };

    static Point point(const DynParams *p, const Trig<N> &T, const double *z, const double *zd,
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
            const double r = zd ? zd[1 + j] : 0.0;
            P.r += l[j] * T.e(j);
            P.J.col(1 + j) = l[j] * T.n(j);              /* d(l e(psi))/dpsi = l n(psi) */
            P.Jdzd -= l[j] * r * r * T.e(j);             /* d(l n(psi))/dt psi' = -l e(psi) psi'^2 */
        }
        if (zd) P.v = P.J * Eigen::Map<const VecQ>(zd);
        return P;
    }

    static Vec2 position(const DynParams *p, const double *z, int m, double xi) {
        return point(p, Trig<N>(z), z, nullptr, m, xi).r;
    }

    static int eval(const DynParams *p, const DynInputs *u, const double *z, const double *zd,
                    double *zdd, DynOut *out);
};
}  // namespace

extern "C" double dyn_slip(double u, double w, double vSlip) {
    /* eqs. 25, 26: alpha = gamma - arctan(vy/vx) is the angle from the velocity
     * of the axle to its wheel plane, i.e. atan2(-w, u) for the velocity (u, w)
     * in wheel coordinates. |u| keeps the force opposed to the lateral sliding
     * when reversing; vSlip keeps it finite at standstill: below about vSlip the
     * tyre acts as a lateral damper C / vSlip instead of dividing by zero. At
     * u = 1 m/s and vSlip = 0.01 m/s the slip is scaled by 1 - 5e-5. The
     * second argument is > 0, so atan2 is the plain arctangent of the ratio
     * (cheaper: it is evaluated for every axle in every right-hand side). */
    return std::atan(-w / std::sqrt(u * u + vSlip * vSlip));
}

extern "C" void dyn_steer(DynInputs *u, int nAxle) {
    for (int a = 1; a <= nAxle; a++) {
        u->cosDelta[a] = std::cos(u->delta[a]);
        u->sinDelta[a] = std::sin(u->delta[a]);
    }
}

extern "C" double dyn_tyre(const DynParams *p, int a, double alpha) {
    const double C = p->C[a], mu = p->mu[a], Fz = p->Fz[a];
    switch (p->tyreModel) {
    case TYRE_LINEAR_FRICTION: {
        /* seed 001: friction scales the cornering stiffness (C_eff = mu C), and
           the force cannot exceed what the friction carries */
        const double F = mu * C * alpha, Fmax = mu * Fz;
        return F > Fmax ? Fmax : (F < -Fmax ? -Fmax : F);
    }
    case TYRE_FIALA: {
        /* brush model (Fiala 1954; Pacejka, Tyre and Vehicle Dynamics, 2012,
           sec. 3.2): cubic in tan(alpha) up to full sliding at
           tan(alpha_sl) = 3 mu Fz / C, then mu Fz; slope C at alpha = 0 */
        const double Fmax = mu * Fz;
        if (!(Fmax > 0.0) || !(C > 0.0)) return 0.0;
        const double t = std::tan(alpha), tsl = 3.0 * Fmax / C;
        if (std::fabs(t) >= tsl) return t > 0 ? Fmax : -Fmax;
        const double s = t / tsl;   /* -1 .. 1 */
        return Fmax * (3.0 * s - 3.0 * s * std::fabs(s) + s * s * s);
    }
    case TYRE_LINEAR_SCALED:
        /* seed 001, 3.1 and eq. C.1: the extensive model's linear tyre, its
           friction coefficient scaling the tyre coefficient, nothing saturates */
        return mu * C * alpha;
    default:
        return C * alpha;          /* eq. 24 */
    }
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

template <int N>
int Chain<N>::eval(const DynParams *p, const DynInputs *u, const double *z, const double *zd,
                   double *zdd, DynOut *out) {
    constexpr int nq = NQ;
    const Trig<N> T(z);
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
        const double cd = u->cosDelta[a], sd = u->sinDelta[a];
        const double uw = cd * vK.x() + sd * vK.y();           /* eq. 23 applied to the velocity */
        const double ww = -sd * vK.x() + cd * vK.y();
        const double alpha = dyn_slip(uw, ww, p->vSlip);
        const double Fy = dyn_tyre(p, a, alpha);
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

    Eigen::LLT<MatQ> llt(M);
    if (llt.info() != Eigen::Success) return 1;
    const VecQ acc = llt.solve(q - h);
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
    }
    return 0;
}

extern "C" int dyn_eval(const DynParams *p, const DynInputs *u, const double *z,
                        const double *zd, double *zdd, DynOut *out) {
    switch (p->nMod) {
    case 1: return Chain<1>::eval(p, u, z, zd, zdd, out);
    case 2: return Chain<2>::eval(p, u, z, zd, zdd, out);
    case 3: return Chain<3>::eval(p, u, z, zd, zdd, out);
    case 4: return Chain<4>::eval(p, u, z, zd, zdd, out);
    default: return 1;   /* nModules is checked against 1..DYN_MAX_MODULES before */
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
