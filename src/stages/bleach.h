/* Photobleaching across a multi-angle acquisition (DESIGN.md section 8).
 *
 * The stacks are recorded on the same fluorophores, so the population fades
 * over the whole acquisition and a later angle looks dimmer, which the
 * MA-TIRF model reads as depth. Model: the signal part of every pixel decays
 * as e^{-k u}, u the frame's time on the acquisition's clock (in frames of
 * the stacks). k is visible inside each stack: its frame sums S_q(t) fall
 * with slope -k m_q, m_q the mean signal part (frame sum minus the
 * background's sum from the intensity step). Each stack gives a slope; k is
 * their inverse-variance weighted fit, its uncertainty from the fit
 * residuals (widened for residuals correlated from frame to frame),
 * constrained to k >= 0: a population does not un-bleach, so a rising fit is
 * noise (sparse blinking: the slopes' sd exceeds the paper's rate) or not
 * bleaching, and factors above 1 would read it as depth
 * (docs/defaults.md#bleach). Stack q's intensity is then divided by its factor
 *   F_q = mean over its frames t of e^{-k u_q(t)}   (time 0 reference)
 * with u_q(t) = start_q + t (stacks one after another, starts from the
 * acquisition order and the gaps) or t + pos_q / n (interleaved: frame t
 * of every stack recorded in turn). */
#pragma once
#include <stdint.h>

#define C0_BLEACH_MAX 64
/* The estimated rate counts as measured when it is this many sds from zero;
 * below, the run warns that the stacks do not show the fade. */
#define C0_BLEACH_SIGNIF 2
/* The first stack recorded fades faster in its first half than in its
 * second by this many sds: a start-up transient (blinking not yet in its
 * steady state), and its rate is its second half's (docs/defaults.md#bleach). */
#define C0_BLEACH_TRANSIENT 3

/* repeat: the last stack recorded is a repeat of the first's angle; the ratio
 * of their intensity totals on the support is the fade between them,
 * F_last / F_first = e^{-k (u_last - u_first)} (midpoints, equal lengths),
 * which gives k when the frame sums cannot (sparse or fast blinking). */
enum c0_bleach_mode { C0_BLEACH_ESTIMATE, C0_BLEACH_KNOWN, C0_BLEACH_OFF, C0_BLEACH_REPEAT };

struct c0_bleach_conf {
	enum c0_bleach_mode mode;     /* estimate */
	int interleaved;              /* 0: stacks recorded one after another */
	int order[C0_BLEACH_MAX];     /* 0-based stack indices in recording order */
	int norder;                   /* 0: the stacks' own order */
	double gap_frames[C0_BLEACH_MAX]; /* illuminated frames between consecutive recorded stacks */
	int ngaps;                    /* 0: none; 1: the same everywhere; n - 1 */
	double factor[C0_BLEACH_MAX]; /* known F_q (mode known) */
	int nfactors;
	double repeat_ratio;          /* mode repeat: last stack's intensity total over the first's */
};

struct c0_bleach_result {
	double k, k_sd;               /* per frame, and its standard error */
	double rho;                   /* the frame sums' residuals' lag-1 autocorrelation (in k_sd) */
	double k_fit;                 /* the slopes' fit before the constraint: k = max(0, k_fit) */
	double k_stack[C0_BLEACH_MAX];/* each stack's own estimate (NAN without signal) */
	double factor[C0_BLEACH_MAX]; /* F_q */
	double start[C0_BLEACH_MAX];  /* first frame's time on the acquisition clock (frames) */
	double signal[C0_BLEACH_MAX]; /* m_q, mean signal part of a frame sum */
	int significant;              /* 0: estimated, and |k_fit| within C0_BLEACH_SIGNIF sds of zero */
	int first_left_out;           /* 1: the first stack's first half was a start-up transient, not in k */
};

/* The order is a permutation of the n stacks, the gap count 0, 1 or n - 1
 * and the gaps >= 0, the factors n positive values; errors name the
 * parameter (acquisition_order, gaps_frames, bleach_factors). */
int c0_bleach_check(const struct c0_bleach_conf *c, int n);
/* k from the frame sums S[q] (T[q] values each) and the background's sum
 * per frame B[q] (n stacks): k_fit, and k = max(0, k_fit). first: the stack
 * recorded first (-1: none, interleaved), whose rate is its second half's
 * after a start-up transient (first_left_out). */
int c0_bleach_fit(int n, const double *const *S, const int64_t *T, const double *B, int first,
		  struct c0_bleach_result *res);
/* The acquisition's clock: stack q's first frame at start[q] (in frames;
 * frame t at start[q] + t), from the order, the gaps and the interleaving. */
void c0_bleach_clock(const struct c0_bleach_conf *c, int n, const int64_t *T, double *start);
/* res->start and res->factor for rate k (res->k) and the frame counts. */
void c0_bleach_factors(const struct c0_bleach_conf *c, int n, const int64_t *T, struct c0_bleach_result *res);
/* The depth offset a rate error leaves, to first order. Stack q's intensity
 * divided by a factor off by e^{-tau_q dk} (tau_q its frames' mean time on
 * the acquisition clock) reads, in the single-depth fit (stages/depthfit.h)
 * at depth z, every depth moved by dz = -dk cov_w(tau, p) / var_w(p): p_q
 * the angle's inverse penetration depth, w_q = (g_q I0_q e^{-p_q z})^2 the
 * fit's weights (gain may be NULL). *per_rate := dz / dk, in nm per unit
 * rate (per frame); 0 where the angles do not differ. Stacks recorded one
 * after another at rising angles give a fade that reads as depth; frames
 * recorded in turn (tau alike to a fraction of a frame) give next to none. */
struct c0_tirf;
int c0_bleach_depth_per_rate(const struct c0_tirf *t, int nq, const double *angles, const double *gain,
			     const double *tau, double z, double *per_rate);
/* Mode repeat: k_fit from c->repeat_ratio and the time between the midpoints
 * of the first and the last recorded stack (T their frame counts), k =
 * max(0, k_fit), then the factors; k_sd is NAN (one ratio). */
int c0_bleach_repeat(const struct c0_bleach_conf *c, int n, const int64_t *T, struct c0_bleach_result *res);
/* Frame sums over a window that moves with the sample, where a drift was
 * corrected: light that drifts across the field's edge would otherwise read
 * as a fade (or as its opposite). The window is x0..x1, y0..y1 of the
 * sample's frame (pixel i covers [i, i + 1)), seen in frame t of stack q
 * shifted by shift(ctx, q, t). Its sum is taken from the frames' row and
 * column sums (c0_frames_profiles): the band of its columns plus the band
 * of its rows less the whole frame, which leaves out the four corners
 * outside both bands (their area is the margins' product). */
struct c0_bleach_window {
	double x0, x1, y0, y1;
	void (*shift)(const void *ctx, int q, int64_t t, double *dx, double *dy);
	const void *ctx;
};
/* The same sum of a still image (H x W), e.g. a stack's background. */
int c0_bleach_window_sum(const struct c0_bleach_window *w, const float *img, int H, int W, double *sum);

/* The whole step for the stacks f: one pass each for its frame sums (over
 * the window win, or whole frames when NULL), then the fit (mode estimate)
 * and the factors; mode known copies the factors, mode off sets them to 1,
 * mode repeat fits k from the ratio. B: each stack's background summed as
 * its frames are. */
struct c0_frames;
int c0_bleach_run(const struct c0_bleach_conf *c, int n, struct c0_frames *f, const double *B,
		  const struct c0_bleach_window *win, struct c0_bleach_result *res);
