// The SEIF's and the batch's option names (seif_options.hpp, batch_options.hpp): each enum's spelling in
// specs, flags, metrics.json and Python, parsed and printed from one list per enum.
#include <seif/core/errors.hpp>
#include <seif/filters/batch_options.hpp>
#include <seif/filters/seif_options.hpp>

#include <array>
#include <string>

namespace seif {

namespace {

/// An enum's names in the order of its values.
template <typename E, std::size_t N>
struct Names {
  std::string_view what;  ///< for the error: "mean recovery"
  std::array<std::string_view, N> names;

  E parse(std::string_view s) const {
    for (std::size_t i = 0; i < N; ++i) {
      if (names[i] == s) return static_cast<E>(i);
    }
    std::string expected;
    for (std::size_t i = 0; i < N; ++i) {
      expected += std::string(i == 0 ? "" : i + 1 == N ? " or " : ", ") + std::string(names[i]);
    }
    throw InvalidArgument("unknown " + std::string(what) + " '" + std::string(s) + "' (expected " + expected + ")");
  }
  std::string_view name(E v) const { return names.at(static_cast<std::size_t>(v)); }
};

constexpr Names<SeifOptions::Mean, 2> kMean{"mean recovery", {"amortized", "exact"}};
constexpr Names<SeifOptions::Deactivate, 2> kDeactivate{"deactivation rule", {"weakest", "oldest"}};
constexpr Names<SeifOptions::Recovery, 2> kRecovery{"recovery point", {"after-update", "before-update"}};
constexpr Names<SeifOptions::RelaxOrder, 3> kRelaxOrder{"relaxation order", {"random", "cyclic", "wildfire"}};
constexpr Names<SeifOptions::Sparsify, 3> kSparsify{"sparsification", {"seif", "eseif", "conservative"}};
constexpr Names<SeifOptions::Covariance, 3> kCovariance{"covariance recovery", {"exact", "local", "conservative"}};
constexpr Names<SeifOptions::Motion, 2> kMotion{"motion timing", {"immediate", "deferred"}};
constexpr Names<SeifOptions::Gauge, 2> kGauge{"gauge rule", {"paper", "kept"}};
constexpr Names<SeifOptions::Coarse, 2> kCoarse{"coarse level", {"off", "rigid"}};
constexpr Names<BatchOptions::Init, 3> kBatchInit{"batch start", {"ekf", "seif", "odometry"}};
constexpr Names<BatchOptions::Solver, 2> kBatchSolver{"batch solver", {"cholesky", "kkt"}};

}  // namespace

SeifOptions::Mean SeifOptions::parseMean(std::string_view s) { return kMean.parse(s); }
SeifOptions::Deactivate SeifOptions::parseDeactivate(std::string_view s) { return kDeactivate.parse(s); }
SeifOptions::Recovery SeifOptions::parseRecovery(std::string_view s) { return kRecovery.parse(s); }
SeifOptions::RelaxOrder SeifOptions::parseRelaxOrder(std::string_view s) { return kRelaxOrder.parse(s); }
SeifOptions::Sparsify SeifOptions::parseSparsify(std::string_view s) { return kSparsify.parse(s); }
SeifOptions::Covariance SeifOptions::parseCovariance(std::string_view s) { return kCovariance.parse(s); }
SeifOptions::Motion SeifOptions::parseMotion(std::string_view s) { return kMotion.parse(s); }
SeifOptions::Gauge SeifOptions::parseGauge(std::string_view s) { return kGauge.parse(s); }
SeifOptions::Coarse SeifOptions::parseCoarse(std::string_view s) { return kCoarse.parse(s); }

std::string_view optionName(SeifOptions::Mean v) { return kMean.name(v); }
std::string_view optionName(SeifOptions::Deactivate v) { return kDeactivate.name(v); }
std::string_view optionName(SeifOptions::Recovery v) { return kRecovery.name(v); }
std::string_view optionName(SeifOptions::RelaxOrder v) { return kRelaxOrder.name(v); }
std::string_view optionName(SeifOptions::Sparsify v) { return kSparsify.name(v); }
std::string_view optionName(SeifOptions::Covariance v) { return kCovariance.name(v); }
std::string_view optionName(SeifOptions::Motion v) { return kMotion.name(v); }
std::string_view optionName(SeifOptions::Gauge v) { return kGauge.name(v); }
std::string_view optionName(SeifOptions::Coarse v) { return kCoarse.name(v); }

BatchOptions::Init BatchOptions::parseInit(std::string_view s) { return kBatchInit.parse(s); }
BatchOptions::Solver BatchOptions::parseSolver(std::string_view s) { return kBatchSolver.parse(s); }
std::string_view optionName(BatchOptions::Init v) { return kBatchInit.name(v); }
std::string_view optionName(BatchOptions::Solver v) { return kBatchSolver.name(v); }

}  // namespace seif
