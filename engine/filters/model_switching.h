// The Markov switching prior shared by the multiple-model filters (imm_filter.h,
// multi_model_pf.h): which of K motion hypotheses is active is a Markov chain with
//     pi_jj = stay_probability,   pi_jk = (1 - stay_probability) / (K - 1)  (j != k)
// per step, and its probabilities mu follow the HMM forward recursion
//     predict:  mu_k <- sum_j pi_jk mu_j
//     update:   mu_k <- L_k mu_k / sum_j L_j mu_j     (L_k: hypothesis k's likelihood of the frame)
// computed from log L_k so that far-off hypotheses do not underflow to 0 / 0.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engine/core/status.h"

namespace localizer::engine {

// INVALID_ARGUMENT naming `field` unless stay_probability is in [0, 1].
Status ValidateStayProbability(double stay_probability, const char* field);

// pi (K x K, rows sum to 1) from the stay probability; K = 1 gives [1].
Eigen::MatrixXd SwitchingMatrix(int model_count, double stay_probability);

// mu <- pi^T mu.
Eigen::VectorXd PredictModelProbabilities(const Eigen::MatrixXd& switching, const Eigen::VectorXd& mu);

// mu <- L mu / sum(L mu) from log L; entries of mu that are 0 stay 0. When every product
// is 0 (or not finite) mu is left unchanged and false is returned.
bool UpdateModelProbabilities(const std::vector<double>& log_likelihoods, Eigen::VectorXd* mu);

}  // namespace localizer::engine
