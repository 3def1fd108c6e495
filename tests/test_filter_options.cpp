// The filter option table (filters/factory.hpp): the spec parser, the CLI's flags and
// metrics.json all come from it, and the configuration metrics.json records parses back to
// the filter that ran.
#include "cli_support.hpp"

#include <seif/core/errors.hpp>
#include <seif/association/association.hpp>
#include <seif/filters/factory.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <charconv>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {

using seif::FilterOption;
using seif::FilterSpec;

/// Every value the test tries for an option: each choice, or the ends and middle of its range.
std::vector<std::string> valuesOf(const FilterOption& o) {
  std::vector<std::string> out;
  switch (o.kind) {
    case FilterOption::Kind::Choice:
      for (std::string_view rest = o.choices; !rest.empty();) {
        const std::size_t bar = rest.find('|');
        out.emplace_back(rest.substr(0, bar));
        rest = bar == std::string_view::npos ? std::string_view() : rest.substr(bar + 1);
      }
      break;
    case FilterOption::Kind::Integer:
      out = {std::to_string(o.min), std::to_string(o.max), std::to_string(o.min + (o.max - o.min) / 2)};
      break;
    case FilterOption::Kind::Seed: out = {"0", "18446744073709551615", "12345"}; break;
    case FilterOption::Kind::Length: out = {"0", "0.005", "2.5"}; break;
    case FilterOption::Kind::Fraction: out = {"0", "0.01", "0.5"}; break;
    case FilterOption::Kind::Real: {  // inside the open interval (min, max)
      const double lo = static_cast<double>(o.min), span = static_cast<double>(o.max - o.min);
      for (double t : {0.001, 0.5, 0.975}) {
        char buf[32];
        const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, lo + t * span);  // shortest round trip
        out.emplace_back(buf, end);
      }
      break;
    }
    case FilterOption::Kind::Profile: out = {"consistent"}; break;
  }
  return out;
}

/// Every option's value in a spec: two specs with the same are the same configuration.
std::vector<std::string> allValues(const FilterSpec& s) {
  std::vector<std::string> v = {s.name};
  for (const FilterOption& o : seif::filterOptions()) v.push_back(o.get(s));
  return v;
}

TEST(FilterOptions, KeysAreUniqueAndEveryValueRoundTrips) {
  std::vector<std::string> keys;
  for (const FilterOption& o : seif::filterOptions()) {
    for (const std::string& k : keys) EXPECT_NE(k, o.key);
    keys.emplace_back(o.key);
    EXPECT_FALSE(o.help.empty()) << o.key;
    for (const std::string& value : valuesOf(o)) {
      const std::string name = o.scope == FilterOption::Scope::Batch ? "batch:" : "seif:";
      const std::string text = name + std::string(o.key) + "=" + value;
      const FilterSpec s = seif::parseFilterSpec(text);
      if (o.kind == FilterOption::Kind::Profile) {  // a shorthand: it sets other keys
        EXPECT_EQ(allValues(s), allValues(seif::parseFilterSpec("seif:" + std::string(seif::kConsistentProfile))));
        EXPECT_NE(std::string(o.help).find(seif::kConsistentProfile), std::string::npos) << o.help;
        continue;
      }
      EXPECT_EQ(o.get(s), value) << text;
      EXPECT_EQ(allValues(seif::parseFilterSpec(seif::canonicalFilterSpec(s))), allValues(s)) << text;
    }
  }
}

TEST(FilterOptions, TheCanonicalSpecParsesBackToTheSameFilter) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const char* names[] = {"ekf", "eif", "seif", "batch"};
    std::string text = names[trial % 4];
    char sep = ':';
    for (const FilterOption& o : seif::filterOptions()) {
      if (!seif::takesOption(text.substr(0, text.find(':')), o) || rng() % 2 == 0) continue;
      const std::vector<std::string> values = valuesOf(o);
      text.append(1, sep).append(o.key).append("=").append(values[rng() % values.size()]);
      sep = ',';
    }
    const FilterSpec s = seif::parseFilterSpec(text);
    const std::string canonical = seif::canonicalFilterSpec(s);
    const FilterSpec back = seif::parseFilterSpec(canonical);
    EXPECT_EQ(allValues(back), allValues(s)) << text << " -> " << canonical;
    EXPECT_EQ(seif::canonicalFilterSpec(back), canonical);
    // The canonical spec names every option the filter takes, and no other.
    for (const FilterOption& o : seif::filterOptions()) {
      const bool listed = seif::takesOption(s.name, o) && o.kind != FilterOption::Kind::Profile;
      EXPECT_EQ(canonical.find(std::string(o.key) + "=") != std::string::npos, listed) << canonical << " / " << o.key;
    }
  }
  EXPECT_EQ(seif::canonicalFilterSpec(seif::parseFilterSpec("batch")), "batch:init=ekf,solver=cholesky");
}

TEST(FilterOptions, AProfileIsOverriddenByTheKeysAfterIt) {
  const FilterSpec s = seif::parseFilterSpec("seif:profile=consistent,active=8");
  EXPECT_EQ(s.linearization, seif::Linearization::Invariant);
  EXPECT_EQ(s.iterations, 3);
  EXPECT_EQ(s.seif.active, 8);
  EXPECT_EQ(s.seif.coarse, seif::SeifOptions::Coarse::Rigid);
  EXPECT_EQ(s.seif.relax, 40);
  EXPECT_EQ(s.seif.gauge, seif::SeifOptions::Gauge::Kept);
  EXPECT_EQ(seif::parseFilterSpec("seif:active=8,profile=consistent").seif.active, 30);
  EXPECT_THROW(seif::parseFilterSpec("seif:profile=fast"), seif::InvalidArgument);
  EXPECT_THROW(seif::parseFilterSpec("ekf:profile=consistent"), seif::InvalidArgument);
}

TEST(FilterOptions, BadValuesAndForeignKeysAreRefusedByName) {
  for (const char* bad : {"seif:active=0", "seif:active=40", "seif:beta=1", "seif:relax=-1", "seif:seed=-1",
                          "seif:seed=18446744073709551616", "seif:mean=fast", "seif:reanchor=-1", "seif:reanchor=nan", "seif:active=4.5", "ekf:active=4",
                          "batch:linearization=fej", "eif:beta=3", "seif:colour=red"}) {
    try {
      seif::parseFilterSpec(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const seif::InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  try {
    seif::parseFilterSpec("ekf:sparsify=eseif");
  } catch (const seif::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("it takes linearization"), std::string::npos) << e.what();
  }
}

// A filter or an associator built in code is held to the ranges a spec or a flag is: each
// range is written once, in its table, and the constructors check through it, in its words.
TEST(FilterOptions, OptionsSetInCodeAreHeldToTheTablesRangesInTheParsersWords) {
  const auto refusal = [](auto&& make) -> std::string {
    try {
      make();
    } catch (const seif::InvalidArgument& e) {
      return e.what();
    }
    return "accepted";
  };
  const auto parserSays = [&](const std::string& spec) {
    return refusal([&] { seif::parseFilterSpec(spec); });
  };
  const seif::FilterConfig config = seif::paperFilterConfig(seif::NoiseModel{});
  struct Case {
    std::string spec;  // the same value as a spec
    std::function<void(FilterSpec&)> set;
    std::string words;  // what both say
  };
  const std::vector<Case> cases = {
      {"seif:beta=40", [](FilterSpec& s) { s.seif.beta = 40; }, "seif: beta=40 is outside [2, 39]"},
      {"seif:blanket=-1", [](FilterSpec& s) { s.seif.blanket = -1; }, "seif: blanket=-1 is outside [0, 2147483647]"},
      {"seif:reanchor=inf", [](FilterSpec& s) { s.seif.reanchor = std::numeric_limits<double>::infinity(); },
       "seif: reanchor=inf is not a finite length >= 0"},
      {"seif:omega=2", [](FilterSpec& s) { s.seif.omega = 2.0; }, "seif: omega=2 is outside (0, 2)"},
      {"ekf:iterations=0", [](FilterSpec& s) { s.iterations = 0; }, "ekf: iterations=0 is outside [1, 20]"},
      {"eif:iterations=21", [](FilterSpec& s) { s.iterations = 21; }, "eif: iterations=21 is outside [1, 20]"},
  };
  for (const Case& c : cases) {
    FilterSpec spec = seif::parseFilterSpec(c.spec.substr(0, c.spec.find(':')));
    c.set(spec);
    const std::string built = refusal([&] { seif::makeFilter(spec, seif::Pose2::Zero(), config); });
    EXPECT_NE(built.find(c.words), std::string::npos) << c.spec << ": " << built;
    // The parser's message for the same value holds the same words after the filter's name.
    EXPECT_NE(parserSays(c.spec).find(c.words.substr(c.words.find(": ") + 2)), std::string::npos) << parserSays(c.spec);
  }
  // The association options likewise (their flags' table).
  seif::AssociationOptions a;
  a.slack = std::numeric_limits<double>::infinity();
  EXPECT_NE(refusal([&] { seif::Associator{a}; }).find("association: slack=inf is not a finite length >= 0"),
            std::string::npos);
  a = {};
  a.jcbb_nodes = 0;
  EXPECT_NE(refusal([&] { seif::Associator{a}; }).find("association: jcbb-nodes=0 is outside [1, "), std::string::npos);
  a = {};
  a.jcbb_nodes = std::numeric_limits<std::size_t>::max();  // beyond the table's int64 range: said so
  EXPECT_NE(refusal([&] { seif::Associator{a}; }).find("jcbb-nodes=18446744073709551615 is outside [1, "),
            std::string::npos);
  a = {};
  a.accept = 0.0;  // in its table's range, but a gate of zero width: the associator's own rule
  EXPECT_NE(refusal([&] { seif::Associator{a}; }).find("gates need 0 < accept"), std::string::npos);
  EXPECT_EQ(refusal([] { seif::Associator{seif::AssociationOptions{}}; }), "accepted");
}

TEST(FilterOptions, EveryOptionIsACliFlagWithTheLibraryDefault) {
  const auto help = seif::test::runCli("run --help");
  ASSERT_EQ(help.status, 0) << help.err;
  FilterSpec defaults;
  defaults.name = "seif";
  for (const FilterOption& o : seif::filterOptions()) {
    if (o.kind == FilterOption::Kind::Profile) continue;
    const std::string flag = "--" + std::string(o.key);
    const std::size_t at = help.out.find(flag + " ");
    ASSERT_NE(at, std::string::npos) << flag << " missing from `seif run --help`";
    const std::string line = help.out.substr(at, help.out.find('\n', at) - at);
    EXPECT_NE(line.find(o.get(defaults)), std::string::npos) << line;
  }
}

TEST(FilterOptions, MetricsJsonRecordsASpecThatReproducesTheRun) {
  const auto dir = seif::test::scratchDir("filter_options_cli");
  ASSERT_EQ(seif::test::runCli("simulate --preset paper --steps 120 --seed 4 --out " + (dir / "W").string()).status, 0);
  // Flags and the spec's own keys together: the spec's win.
  const auto first = seif::test::runCli("run --dataset " + (dir / "W").string() +
                                        " --active 4 --relax 3 --relax-order random --seed 9 "
                                        "--filter seif:relax=5,sparsify=eseif,beta=3 --out " + (dir / "a").string());
  ASSERT_EQ(first.status, 0) << first.err;
  const auto metrics = nlohmann::json::parse(seif::test::slurp(dir / "a" / "metrics.json"));
  const std::string spec = metrics.at("filter_spec");
  const FilterSpec s = seif::parseFilterSpec(spec);
  EXPECT_EQ(s.seif.active, 4);
  EXPECT_EQ(s.seif.relax, 5);
  EXPECT_EQ(s.seif.beta, 3);
  EXPECT_EQ(s.seif.seed, 9u);
  EXPECT_EQ(s.seif.sparsify, seif::SeifOptions::Sparsify::Eseif);
  EXPECT_EQ(s.seif.relax_order, seif::SeifOptions::RelaxOrder::Random);
  EXPECT_EQ(metrics.at("seif").at("relax-order"), "random");
  // The recorded spec alone, with no flags, runs the same filter: the same numbers.
  const auto again = seif::test::runCli("run --dataset " + (dir / "W").string() + " --filter " + spec + " --out " +
                                        (dir / "b").string());
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_EQ(seif::test::slurp(dir / "a" / "map.csv"), seif::test::slurp(dir / "b" / "map.csv"));
  EXPECT_EQ(seif::test::slurp(dir / "a" / "trajectory.tum"), seif::test::slurp(dir / "b" / "trajectory.tum"));
  const auto metrics_b = nlohmann::json::parse(seif::test::slurp(dir / "b" / "metrics.json"));
  EXPECT_EQ(metrics_b.at("filter_spec"), spec);
}

}  // namespace
