// How visible a temporal frequency is: the weighting behind flicker_index.
#pragma once

#include <vector>

namespace shimmer::metrics {

// Gain of Watson's linear temporal filter, normalized to 1 at its peak.
//
// Watson, A. B. (1986). Temporal sensitivity. In K. Boff, L. Kaufman and
// J. Thomas (eds.), Handbook of Perception and Human Performance, Vol. 1,
// ch. 6, eqs. 40-45: the impulse response is the difference of two cascades of
// leaky integrators, h(t) = xi [h1(t) - zeta h2(t)], h_i a gamma kernel of
// order n_i and time constant tau_i, so that
//   H(f) = xi [ (1 + i 2 pi f tau)^-n1 - zeta (1 + i 2 pi f kappa tau)^-n2 ].
// Parameters: filter orders n1 = 9, n2 = 10 and time-constant ratio
// kappa = 1.33 as in Watson's Fig. 6.5; tau = 4.94 ms as in ISETCam's
// implementation of the same model (human/watsonImpulseResponse.m).
// zeta = 0.9 (strongly transient; ISETCam defaults to 0.5) is our choice: it gives the band-pass shape of photopic de
// Lange curves: peak near 8.5 Hz, about 0.4 at 2 Hz, 0.1 at 30 Hz, ~0 at 60 Hz. Why this curve: it is a temporal-only
// model with a closed form (the Kelly 1979 surface needs a spatial frequency we do not know for arbitrary frames), and
// it is a linear filter, so |H|^2 applies to a power spectrum exactly.
double WatsonTemporalGain(double frequency_hz);

// Power of the PSD seen through that filter: sum_k |H(f_k)|^2 psd_k fs/L,
// in the PSD's units (luminance^2). Equal to the band powers' total for a
// flat |H| = 1, smaller for flicker the eye filters out (DC, > 30 Hz).
double FlickerIndex(const std::vector<double>& freq_hz, const std::vector<double>& psd);

}  // namespace shimmer::metrics
