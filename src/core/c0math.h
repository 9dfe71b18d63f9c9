#pragma once
#define C0_PI 3.14159265358979323846
#define C0_FWHM_TO_SIGMA 0.42466090014400953   /* 1 / (2 sqrt(2 ln 2)) */
