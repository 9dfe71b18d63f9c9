/* The pixel variance a fit on the fine grid predicts (the covariance's lag 0,
 * sum_k x_k a_k(i)^2 for a Gaussian PSF integrated over camera pixels), as a
 * camera pixel centred on each fine position would see it: x blurred by the
 * pixel-integrated PSF squared (a separable kernel). Noise-free and background-free
 * where the measured variances are neither; its crests mark the axes of the
 * structures the fit found. */
#pragma once

/* v (Ly x Lx) from x (Ly x Lx, fine grid of factor r; sigma_px the PSF's sd
 * in camera pixels): v = x * (k k^T), k[d] = (integral over the camera pixel
 * centred d/r from the emitter)^2, cut where it falls below 1e-7 of its peak
 * (4 sigma), zero outside the field. Cost: the nonzeros of x times
 * (8 sigma_px r + 1)^2. C0_OK, or C0_ENOMEM for the kernel. */
int c0_finevar(const double *x, int Ly, int Lx, int r, double sigma_px, double *v);
