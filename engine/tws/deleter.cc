#include "engine/tws/deleter.h"

namespace localizer::engine::tws {

Deleter::Deleter(const DeleterOptions& options)
    : options_(options),
      rule_(options.confirm_hits, options.confirm_window),
      max_variance_m2_(options.max_position_sigma_m * options.max_position_sigma_m) {}

const char* DeletionName(Deletion d) {
  switch (d) {
    case Deletion::kKeep:
      return "keep";
    case Deletion::kUnconfirmable:
      return "unconfirmable";
    case Deletion::kCoasted:
      return "coasted";
    case Deletion::kDiverged:
      return "diverged";
  }
  return "unknown";
}

}  // namespace localizer::engine::tws
