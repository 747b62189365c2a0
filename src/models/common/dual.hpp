/* A dual number a + b1 eps1 + .. + bK epsK (eps_i eps_j = 0) for forward-mode
 * differentiation: the models' C equations, written on a real type (MA_REAL,
 * ...), are compiled a second time in C++ on Dual, and the eps parts of every
 * result are its derivatives along the seeds put into the eps parts of the
 * arguments: exact to rounding, from the one source of the equations (fmu.h:
 * model_directional_derivative). Dual (K = 1) is one seed; DualN<K> carries K
 * seeds through one evaluation (vector mode: a whole Jacobian in one pass, the
 * values and every elementary function computed once). Comparisons look at the
 * value only, so a branch takes the same side as the double build. Only what
 * the models use. */
#ifndef ARTIBUS_DUAL_HPP
#define ARTIBUS_DUAL_HPP

#include <cmath>

/* every operation inlined: on K seeds an operation is a loop the compiler
   would otherwise call, and Eigen's expressions on custom scalars nest them */
#if defined(__GNUC__) && defined(__OPTIMIZE__)
#define ARTIBUS_DUAL_INLINE inline __attribute__((always_inline))
#else
#define ARTIBUS_DUAL_INLINE inline
#endif

namespace artibus {

template <int K>
struct DualN {
    double v;         /* value */
    double d[K];      /* derivatives along the K seeds */
    ARTIBUS_DUAL_INLINE DualN(double value = 0.0, double deriv = 0.0) : v(value) {
        d[0] = deriv;
        for (int k = 1; k < K; k++) d[k] = 0.0;
    }
    ARTIBUS_DUAL_INLINE DualN &operator+=(const DualN &b) { for (int k = 0; k < K; k++) d[k] += b.d[k]; v += b.v; return *this; }
    ARTIBUS_DUAL_INLINE DualN &operator-=(const DualN &b) { for (int k = 0; k < K; k++) d[k] -= b.d[k]; v -= b.v; return *this; }
    ARTIBUS_DUAL_INLINE DualN &operator*=(const DualN &b) {
        for (int k = 0; k < K; k++) d[k] = d[k] * b.v + v * b.d[k];
        v *= b.v;
        return *this;
    }
    ARTIBUS_DUAL_INLINE DualN &operator/=(const DualN &b) {
        for (int k = 0; k < K; k++) d[k] = (d[k] * b.v - v * b.d[k]) / (b.v * b.v);
        v /= b.v;
        return *this;
    }
    /* a constant: no derivative parts to combine */
    ARTIBUS_DUAL_INLINE DualN &operator+=(double b) { v += b; return *this; }
    ARTIBUS_DUAL_INLINE DualN &operator-=(double b) { v -= b; return *this; }
    ARTIBUS_DUAL_INLINE DualN &operator*=(double b) { for (int k = 0; k < K; k++) d[k] *= b; v *= b; return *this; }
    ARTIBUS_DUAL_INLINE DualN &operator/=(double b) { for (int k = 0; k < K; k++) d[k] /= b; v /= b; return *this; }
};

using Dual = DualN<1>;

template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator+(DualN<K> a, const DualN<K> &b) { return a += b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator-(DualN<K> a, const DualN<K> &b) { return a -= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator*(DualN<K> a, const DualN<K> &b) { return a *= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator/(DualN<K> a, const DualN<K> &b) { return a /= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator+(DualN<K> a, double b) { return a += b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator-(DualN<K> a, double b) { return a -= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator*(DualN<K> a, double b) { return a *= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator/(DualN<K> a, double b) { return a /= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator+(double a, DualN<K> b) { return b += a; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator-(double a, const DualN<K> &b) { return DualN<K>(a) -= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator*(double a, DualN<K> b) { return b *= a; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator/(double a, const DualN<K> &b) { return DualN<K>(a) /= b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator-(DualN<K> a) {
    a.v = -a.v;
    for (int k = 0; k < K; k++) a.d[k] = -a.d[k];
    return a;
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> operator+(const DualN<K> &a) { return a; }

/* comparisons on the values; a constant on either side */
#define ARTIBUS_DUAL_COMPARE(op)                                                                  \
    template <int K> ARTIBUS_DUAL_INLINE bool operator op(const DualN<K> &a, const DualN<K> &b) { return a.v op b.v; } \
    template <int K> ARTIBUS_DUAL_INLINE bool operator op(const DualN<K> &a, double b) { return a.v op b; }            \
    template <int K> ARTIBUS_DUAL_INLINE bool operator op(double a, const DualN<K> &b) { return a op b.v; }
ARTIBUS_DUAL_COMPARE(<)
ARTIBUS_DUAL_COMPARE(>)
ARTIBUS_DUAL_COMPARE(<=)
ARTIBUS_DUAL_COMPARE(>=)
ARTIBUS_DUAL_COMPARE(==)
ARTIBUS_DUAL_COMPARE(!=)
#undef ARTIBUS_DUAL_COMPARE

/* the chain rule, f(a) + f'(a) a.d eps: the value f(a) and the factor f'(a) once */
template <int K> ARTIBUS_DUAL_INLINE DualN<K> chain(double f, double df, const DualN<K> &a) {
    DualN<K> r(f);
    for (int k = 0; k < K; k++) r.d[k] = df * a.d[k];
    return r;
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> sin(const DualN<K> &a) { return chain(std::sin(a.v), std::cos(a.v), a); }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> cos(const DualN<K> &a) { return chain(std::cos(a.v), -std::sin(a.v), a); }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> tan(const DualN<K> &a) {
    const double t = std::tan(a.v);
    return chain(t, 1.0 + t * t, a);
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> atan(const DualN<K> &a) { return chain(std::atan(a.v), 1.0 / (1.0 + a.v * a.v), a); }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> atan2(const DualN<K> &y, const DualN<K> &x) {
    const double r2 = x.v * x.v + y.v * y.v;
    DualN<K> r(std::atan2(y.v, x.v));
    for (int k = 0; k < K; k++) r.d[k] = (x.v * y.d[k] - y.v * x.d[k]) / r2;
    return r;
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> sqrt(const DualN<K> &a) {
    const double s = std::sqrt(a.v);
    return chain(s, 1.0 / (2.0 * s), a);
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> hypot(const DualN<K> &a, const DualN<K> &b) {
    const double h = std::hypot(a.v, b.v);
    DualN<K> r(h);
    for (int k = 0; k < K; k++) r.d[k] = h > 0.0 ? (a.v * a.d[k] + b.v * b.d[k]) / h : 0.0;
    return r;
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> exp(const DualN<K> &a) {
    const double e = std::exp(a.v);
    return chain(e, e, a);
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> tanh(const DualN<K> &a) {
    const double t = std::tanh(a.v);
    return chain(t, 1.0 - t * t, a);
}
template <int K> ARTIBUS_DUAL_INLINE DualN<K> fabs(const DualN<K> &a) { return a.v < 0.0 ? -a : a; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> fmax(const DualN<K> &a, const DualN<K> &b) { return a.v >= b.v ? a : b; }
template <int K> ARTIBUS_DUAL_INLINE DualN<K> fmin(const DualN<K> &a, const DualN<K> &b) { return a.v <= b.v ? a : b; }
template <int K> ARTIBUS_DUAL_INLINE bool isfinite(const DualN<K> &a) {
    bool f = std::isfinite(a.v);
    for (int k = 0; k < K; k++) f = f && std::isfinite(a.d[k]);
    return f;
}

}  // namespace artibus

#endif
