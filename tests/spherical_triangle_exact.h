/* The solid-angle sampler's formulas (src/bake/spherical_triangle.c) in
 * double precision, for the tests: on float inputs, their exact value to
 * within float's rounding many times over, against which the host's float
 * reference and the kernel are both measured. Libm's atan2, sin and cos
 * stand in for the polynomials, which only approximate them. */
#ifndef PB_TEST_SPHERICAL_TRIANGLE_EXACT_H
#define PB_TEST_SPHERICAL_TRIANGLE_EXACT_H

#include <math.h>

static inline double exact_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void exact_cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static inline void exact_unit(double v[3])
{
    double l = sqrt(exact_dot(v, v));
    for (int k = 0; k < 3; ++k)
        v[k] /= l;
}

/* Van Oosterom and Strackee's solid angle of (v0, v1, v2) seen from x */
static inline double exact_triangle_area(const double x[3], const double v0[3], const double v1[3], const double v2[3])
{
    double p0[3], p1[3], p2[3], e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) {
        p0[k] = v0[k] - x[k], p1[k] = v1[k] - x[k], p2[k] = v2[k] - x[k];
        e1[k] = v1[k] - v0[k], e2[k] = v2[k] - v0[k];
    }
    double l0 = sqrt(exact_dot(p0, p0)), l1 = sqrt(exact_dot(p1, p1)), l2 = sqrt(exact_dot(p2, p2));
    exact_cross(e1, e2, n);
    double num = fabs(exact_dot(p0, n));
    double den = l0 * l1 * l2 + exact_dot(p0, p1) * l2 + exact_dot(p1, p2) * l0 + exact_dot(p2, p0) * l1;
    return 2 * atan2(num, den);
}

/* Arvo's two steps as the reference takes them, at solid angle `area` */
static inline void exact_triangle_sample(const double x[3], const double v0[3], const double v1[3], const double v2[3],
                                         double area, double u1, double u2, double w[3])
{
    double A[3], B[3], C[3], P[3], bP[3], cm[3], cp[3], Cs[3], d[3], b_perp[3];
    for (int k = 0; k < 3; ++k)
        A[k] = v0[k] - x[k], B[k] = v1[k] - x[k], C[k] = v2[k] - x[k];
    exact_unit(A), exact_unit(B), exact_unit(C);
    double ca = exact_dot(C, A);
    for (int k = 0; k < 3; ++k)
        P[k] = C[k] - ca * A[k];
    exact_unit(P);
    exact_cross(B, P, bP);
    double kk = fabs(exact_dot(A, bP)), bp = exact_dot(B, P), h = 0.5 * u1 * area;
    double den = kk * cos(h) - bp * sin(h);
    for (int k = 0; k < 3; ++k)
        cm[k] = C[k] - A[k], cp[k] = C[k] + A[k];
    double tau_c = sqrt(exact_dot(cm, cm) / exact_dot(cp, cp)), tau = (1 + exact_dot(A, B)) * sin(h) / den;
    if (!(den > 0 && tau < tau_c))
        tau = tau_c;
    double t2 = tau * tau;
    for (int k = 0; k < 3; ++k) {
        Cs[k] = ((1 - t2) * A[k] + 2 * tau * P[k]) / (1 + t2);
        d[k] = Cs[k] - B[k];
    }
    double e = u2 * 0.5 * exact_dot(d, d), cb = exact_dot(Cs, B);
    for (int k = 0; k < 3; ++k)
        b_perp[k] = Cs[k] - cb * B[k];
    double bl = sqrt(exact_dot(b_perp, b_perp));
    for (int k = 0; k < 3; ++k)
        w[k] = bl > 0 ? (1 - e) * B[k] + sqrt(fmax(0, e * (2 - e))) / bl * b_perp[k] : B[k];
    exact_unit(w);
}

/* The angle (rad) between a float direction and an exact one */
static inline double exact_angle(const float a[3], const double b[3])
{
    double c = 0, s2 = 0;
    for (int k = 0; k < 3; ++k)
        c += a[k] * b[k], s2 += (a[k] - b[k]) * (a[k] - b[k]);
    return atan2(sqrt(s2), c);
}

#endif
