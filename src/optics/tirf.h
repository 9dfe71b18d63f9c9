/* Total internal reflection physics shared by the simulator and the MA-TIRF
 * reconstruction. Angles in degrees (in the glass), lengths in nm. */
#pragma once

struct c0_tirf {
	double n_glass;        /* 1.518 */
	double n_sample;       /* 1.33 */
	double wavelength_nm;  /* excitation, vacuum: 488 */
	double s_fraction;     /* I0 = s*I_s + (1-s)*I_p: 0.75 (the MA-TIRF reference's mix) */
};

#define C0_TIRF_DEFAULTS { 1.518, 1.33, 488.0, 0.75 }

int c0_tirf_check(const struct c0_tirf *t);
double c0_tirf_critical_deg(const struct c0_tirf *t);
/* Inverse penetration depth p (1/nm) of the intensity; error below critical. */
int c0_tirf_p(const struct c0_tirf *t, double alpha_deg, double *p);
/* Interface intensity per unit incident intensity (Axelrod): s, p, and mix. */
double c0_tirf_i0(const struct c0_tirf *t, double alpha_deg);
void c0_tirf_i0_sp(const struct c0_tirf *t, double alpha_deg, double *is, double *ip);
/* Depth-bin weights W (nq x nz, row-major): average of I0_q exp(-p_q z) over
 * bin j = [z0 + j dz, z0 + (j+1) dz); gain (nq, may be NULL) scales rows. */
int c0_tirf_weights(const struct c0_tirf *t, int nq, const double *alpha_deg, const double *gain,
		    int nz, double z0, double dz, double *W);
