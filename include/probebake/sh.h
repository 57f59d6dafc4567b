/*
 * probebake SH: real spherical harmonics up to band 2 (L2, 9 coefficients).
 *
 * Basis order (l,m): (0,0) (1,-1) (1,0) (1,1) (2,-2) (2,-1) (2,0) (2,1) (2,2),
 * the usual orthonormal real basis over the unit sphere, evaluated on the
 * world-space direction (x, y, z) exactly as given (glTF axes, +Y up; no axis
 * swap, so Y(1,0) follows +Z and Y(1,-1) follows +Y):
 *
 *   Y00 = 0.282095                 Y1-1 = 0.488603 y   Y10 = 0.488603 z
 *   Y11 = 0.488603 x               Y2-2 = 1.092548 xy  Y2-1 = 1.092548 yz
 *   Y20 = 0.315392 (3z^2 - 1)      Y21 = 1.092548 xz   Y22 = 0.546274 (x^2 - y^2)
 *
 * Irradiance from radiance (clamped-cosine convolution, Ramamoorthi &
 * Hanrahan 2001): band 0 times pi, band 1 times 2pi/3, band 2 times pi/4.
 * Colour coefficients are stored as 9 RGB triples: c[3*i + channel].
 */
#ifndef PROBEBAKE_SH_H
#define PROBEBAKE_SH_H

#include "probebake/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PB_SH_COUNT 9

/* The 9 basis functions at unit direction d. */
void pb_sh_basis(const float d[3], float out[PB_SH_COUNT]);

/* Adds radiance `rgb` arriving from unit direction d, weighted by `weight`
 * (4pi / N for N uniformly distributed directions), to c[27]. */
void pb_sh_add(float c[3 * PB_SH_COUNT], const float d[3], const float rgb[3], float weight);

/* Radiance coefficients -> irradiance coefficients, in place. */
void pb_sh_radiance_to_irradiance(float c[3 * PB_SH_COUNT]);

/* Evaluates coefficients c[27] in unit direction d -> rgb. For irradiance
 * coefficients this is the irradiance on a surface with normal d. */
void pb_sh_eval(const float c[3 * PB_SH_COUNT], const float d[3], float rgb[3]);

/* Adds a delta source seen in unit direction d (a point, spot or
 * directional light) to radiance coefficients c[27]: its radiance is
 * E delta(w - d), where E [W/m^2] is the irradiance it gives a surface facing
 * it (I / r^2 for a point light of intensity I at distance r). Projection:
 * c_i += E Y_i(d). */
void pb_sh_add_delta(float c[3 * PB_SH_COUNT], const float d[3], const float irradiance_rgb[3]);

/* Windowing against ringing (Gibbs): a very bright, very small source (an
 * HDR sun, a tiny emitter) projected onto L2 gives negative lobes and
 * overshoot. Band l is scaled by a factor w_l that tapers with l:
 *   hanning  w_l = (1 + cos(pi l / W)) / 2
 *   lanczos  w_l = sinc(l / W) = sin(pi l / W) / (pi l / W)
 * W = width (default 3 = L + 1: hanning 1, 0.75, 0.25; lanczos 1, 0.83,
 * 0.41). Windowing blurs: it trades ringing for lost directionality
 * (test_sh measures both against the exact irradiance). */
typedef enum pb_sh_window_kind {
    PB_SH_WINDOW_NONE = 0,
    PB_SH_WINDOW_HANNING = 1,
    PB_SH_WINDOW_LANCZOS = 2
} pb_sh_window_kind;

float pb_sh_window_factor(pb_sh_window_kind kind, float width, int band);
void pb_sh_apply_window(float c[3 * PB_SH_COUNT], pb_sh_window_kind kind, float width);

#ifdef __cplusplus
}
#endif
#endif
