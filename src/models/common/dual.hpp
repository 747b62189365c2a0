/* A dual number a + b eps (eps^2 = 0) for forward-mode differentiation: the
 * models' C equations, written on a real type (MA_REAL, ...), are compiled a
 * second time in C++ on Dual, and the eps part of every result is its
 * derivative along the seed put into the eps parts of the arguments: exact to
 * rounding, from the one source of the equations (fmu.h:
 * model_directional_derivative). Comparisons look at the value only, so a
 * branch takes the same side as the double build. Only what the models use. */
#ifndef ARTIBUS_DUAL_HPP
#define ARTIBUS_DUAL_HPP

#include <cmath>

namespace artibus {

struct Dual {
    double v, d;      /* value, derivative along the seed */
    Dual(double value = 0.0, double deriv = 0.0) : v(value), d(deriv) {}
    Dual &operator+=(const Dual &b) { d += b.d; v += b.v; return *this; }
    Dual &operator-=(const Dual &b) { d -= b.d; v -= b.v; return *this; }
    Dual &operator*=(const Dual &b) { d = d * b.v + v * b.d; v *= b.v; return *this; }
    Dual &operator/=(const Dual &b) { d = (d * b.v - v * b.d) / (b.v * b.v); v /= b.v; return *this; }
};

inline Dual operator+(Dual a, const Dual &b) { return a += b; }
inline Dual operator-(Dual a, const Dual &b) { return a -= b; }
inline Dual operator*(Dual a, const Dual &b) { return a *= b; }
inline Dual operator/(Dual a, const Dual &b) { return a /= b; }
inline Dual operator-(const Dual &a) { return Dual(-a.v, -a.d); }
inline Dual operator+(const Dual &a) { return a; }

inline bool operator<(const Dual &a, const Dual &b) { return a.v < b.v; }
inline bool operator>(const Dual &a, const Dual &b) { return a.v > b.v; }
inline bool operator<=(const Dual &a, const Dual &b) { return a.v <= b.v; }
inline bool operator>=(const Dual &a, const Dual &b) { return a.v >= b.v; }
inline bool operator==(const Dual &a, const Dual &b) { return a.v == b.v; }
inline bool operator!=(const Dual &a, const Dual &b) { return a.v != b.v; }

/* the chain rule, f(a) + f'(a) a.d eps */
inline Dual sin(const Dual &a) { return Dual(std::sin(a.v), std::cos(a.v) * a.d); }
inline Dual cos(const Dual &a) { return Dual(std::cos(a.v), -std::sin(a.v) * a.d); }
inline Dual tan(const Dual &a) {
    const double t = std::tan(a.v);
    return Dual(t, (1.0 + t * t) * a.d);
}
inline Dual atan(const Dual &a) { return Dual(std::atan(a.v), a.d / (1.0 + a.v * a.v)); }
inline Dual atan2(const Dual &y, const Dual &x) {
    const double r2 = x.v * x.v + y.v * y.v;
    return Dual(std::atan2(y.v, x.v), (x.v * y.d - y.v * x.d) / r2);
}
inline Dual sqrt(const Dual &a) {
    const double s = std::sqrt(a.v);
    return Dual(s, a.d / (2.0 * s));
}
inline Dual hypot(const Dual &a, const Dual &b) {
    const double h = std::hypot(a.v, b.v);
    return Dual(h, h > 0.0 ? (a.v * a.d + b.v * b.d) / h : 0.0);
}
inline Dual exp(const Dual &a) {
    const double e = std::exp(a.v);
    return Dual(e, e * a.d);
}
inline Dual tanh(const Dual &a) {
    const double t = std::tanh(a.v);
    return Dual(t, (1.0 - t * t) * a.d);
}
inline Dual fabs(const Dual &a) { return a.v < 0.0 ? -a : a; }
inline Dual fmax(const Dual &a, const Dual &b) { return a.v >= b.v ? a : b; }
inline Dual fmin(const Dual &a, const Dual &b) { return a.v <= b.v ? a : b; }
inline bool isfinite(const Dual &a) { return std::isfinite(a.v) && std::isfinite(a.d); }

}  // namespace artibus

#endif
