// Garland & Heckbert 1997 quadric error metric: Q(p) = p^T A p + 2 b.p + c, stored as 10 doubles.
#pragma once

namespace pms {

struct Quadric {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
  double b0 = 0, b1 = 0, b2 = 0, c = 0;

  // Quadric of the plane n.p + d = 0 (n unit length), scaled by `weight`.
  static Quadric plane(double nx, double ny, double nz, double d, double weight) {
    Quadric q;
    q.a00 = weight * nx * nx;
    q.a01 = weight * nx * ny;
    q.a02 = weight * nx * nz;
    q.a11 = weight * ny * ny;
    q.a12 = weight * ny * nz;
    q.a22 = weight * nz * nz;
    q.b0 = weight * nx * d;
    q.b1 = weight * ny * d;
    q.b2 = weight * nz * d;
    q.c = weight * d * d;
    return q;
  }

  Quadric& operator+=(const Quadric& o) {
    a00 += o.a00;
    a01 += o.a01;
    a02 += o.a02;
    a11 += o.a11;
    a12 += o.a12;
    a22 += o.a22;
    b0 += o.b0;
    b1 += o.b1;
    b2 += o.b2;
    c += o.c;
    return *this;
  }

  double error(const float* p) const {
    const double x = p[0], y = p[1], z = p[2];
    const double e = a00 * x * x + 2 * a01 * x * y + 2 * a02 * x * z + a11 * y * y + 2 * a12 * y * z + a22 * z * z +
                     2 * (b0 * x + b1 * y + b2 * z) + c;
    return e > 0 ? e : 0;  // rounding can make a sum of squares slightly negative
  }

  // Error of (this + o) at p without materialising the sum.
  double error_sum(const Quadric& o, const float* p) const {
    Quadric s = *this;
    s += o;
    return s.error(p);
  }
};

}  // namespace pms
