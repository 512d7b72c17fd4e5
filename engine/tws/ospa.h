// Multi-target miss distances between a set of truths X (m points) and estimates Y (n).
//
// OSPA (Schuhmacher, Vo & Vo 2008), cut-off c > 0, order p >= 1, d_c = min(c, |x - y|),
// m <= n (else swap):
//     OSPA = ( (min_pi sum_i d_c(x_i, y_pi(i))^p + c^p (n - m)) / n )^(1/p);   0 when both
//     are empty. Units of c (m); at most c.
// GOSPA with alpha = 2 (Rahmathullah, Garcia-Fernandez & Svensson 2017):
//     GOSPA = ( min_gamma sum_{(i,j) in gamma} |x_i - y_j|^p + c^p/2 (m + n - 2 |gamma|) )^(1/p)
//     over partial assignments gamma of pairs closer than c: localisation error plus c^p/2
//     per missed truth and per false estimate (not normalised by n, unlike OSPA).
// Both solve their assignment exactly (assignment.h): O(max(m, n)^3).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace localizer::engine::tws {

struct GospaResult {
  double gospa = 0.0;
  double localisation = 0.0;  // sum of |x - y|^p over assigned pairs
  int assigned = 0;
  int missed = 0;        // truths without an estimate
  int false_tracks = 0;  // estimates without a truth
};

double Ospa(const std::vector<Eigen::Vector3d>& truth, const std::vector<Eigen::Vector3d>& estimates, double cutoff,
            double order);
GospaResult Gospa(const std::vector<Eigen::Vector3d>& truth, const std::vector<Eigen::Vector3d>& estimates,
                  double cutoff, double order);

}  // namespace localizer::engine::tws
