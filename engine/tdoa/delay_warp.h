// Resampling one channel so that a delay that changes during a frame reads as one delay.
//
// A source moving near an array changes each pair's delay by up to 2 v / c per second: a
// 0.5 m/s source in air moves the peak of a 48 kHz pair by 12 samples over a 4096-sample
// frame, a 5 m/s one in water by 27 samples at 16 kHz, against a peak a few samples wide.
// The correlation of such a frame is smeared over the span and its maximum may fall
// anywhere in it (ACCURACY.md, "a peak that migrates within a frame"). Where a track predicts
// the rate, the sensor's channel is read along the predicted delay, so the frame's pair
// correlates as if the delay were its value at the frame's centre (GccPhatEstimator keeps
// that reading only where its peak is the higher).
#pragma once

namespace localizer::engine {

// out[n] = in(n + rate (n - c)), c = (n_samples - 1) / 2 the frame's centre, read between
// samples with a Catmull-Rom cubic (4 taps; flat to about a quarter of the sample rate) and at
// the nearest end beyond the frame. `rate` is the pair's delay rate in seconds per second
// (dimensionless); pair delay d(t) = t_sensor - t_reference growing at `rate` makes the
// sensor's channel lag the reference's more and more, and reading it at n + rate (n - c)
// undoes that to first order. |rate| must be below 0.5; in and out must not overlap.
// Cost: about 10 flops per sample.
void WarpChannel(const float* in, int n_samples, double rate, float* out);

}  // namespace localizer::engine
