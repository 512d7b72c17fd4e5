// Kaiser window, shared by the band-pass FIR design and the fractional-delay interpolator.
//
//     w(u) = I0(beta sqrt(1 - u^2)) / I0(beta)   for |u| <= 1, else 0
//
// beta trades main-lobe width for side-lobe level; for a windowed-sinc filter with stopband
// attenuation A dB (A > 50) Kaiser's formula gives beta = 0.1102 (A - 8.7), and the number of
// taps for a transition of width dw rad/sample is about (A - 8) / (2.285 dw) + 1.
#pragma once

namespace localizer::engine {

// Modified Bessel function of the first kind, order 0 (power series; |x| <= 50).
double BesselI0(double x);

// w(u) as above; u is the tap offset divided by the half-length of the window.
double KaiserWindow(double u, double beta);

// Kaiser's beta for a windowed-sinc filter with `attenuation_db` of stopband attenuation.
double KaiserBetaForAttenuation(double attenuation_db);

}  // namespace localizer::engine
