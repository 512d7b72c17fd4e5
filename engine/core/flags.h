// A small command-line flag parser: `--name value`, `--name=value` and boolean `--name`.
//
// Each flag binds to a variable the caller owns; the variable's value at registration is
// the default printed in the help, so defaults live in one place (usually an engine options
// struct). Parse() reports unknown flags, missing or malformed values and missing required
// flags as INVALID_ARGUMENT naming the flag; the caller turns that into exit code 2.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/status.h"

namespace localizer {

class FlagSet {
 public:
  struct Flag {
    std::string name;     // without the leading "--"
    std::string metavar;  // placeholder for the value in usage ("HZ"); empty for booleans
    std::string help;
    std::string default_text;  // printed as "(default: ...)"; empty prints nothing
    bool repeatable = false;
    bool required = false;
    bool seen = false;
    std::function<Status(const std::string&)> set;  // empty for booleans

    Flag& Required() {
      required = true;
      return *this;
    }
  };

  // `usage`: the synopsis line after "usage: "; `summary`: what the command does.
  FlagSet(std::string usage, std::string summary);

  Flag& String(const std::string& name, std::string* value, const std::string& metavar, const std::string& help);
  // Repeatable: every occurrence appends.
  Flag& Strings(const std::string& name, std::vector<std::string>* values, const std::string& metavar,
                const std::string& help);
  // `unit` follows the default in the help ("4096 samples").
  Flag& Int(const std::string& name, int* value, const std::string& metavar, const std::string& unit,
            const std::string& help);
  Flag& Uint64(const std::string& name, uint64_t* value, const std::string& metavar, const std::string& help);
  Flag& Double(const std::string& name, double* value, const std::string& metavar, const std::string& unit,
               const std::string& help);
  // Unset by default; `default_text` says what applies then ("from array.json").
  Flag& OptionalDouble(const std::string& name, std::optional<double>* value, const std::string& metavar,
                       const std::string& default_text, const std::string& help);
  Flag& OptionalInt(const std::string& name, std::optional<int>* value, const std::string& metavar,
                    const std::string& default_text, const std::string& help);
  Flag& Bool(const std::string& name, bool* value, const std::string& help);

  // Parses the arguments after the command name. `--help` / `-h` stops parsing and sets
  // help_requested(); required flags are then not checked.
  Status Parse(const std::vector<std::string>& args);
  bool help_requested() const { return help_requested_; }
  bool seen(const std::string& name) const;

  std::string Usage() const;

 private:
  struct FlagText {
    std::string name, metavar, help, default_text;
  };
  Flag& Add(FlagText text, std::function<Status(const std::string&)> set);
  Flag* Find(const std::string& name);
  Status CheckRequired() const;

  std::string usage_;
  std::string summary_;
  std::deque<Flag> flags_;  // deque: references returned by Add stay valid
  bool help_requested_ = false;
};

// Number parsing shared by the flags: the whole text must be a number in range.
StatusOr<int64_t> ParseInteger(const std::string& text);
StatusOr<double> ParseFiniteDouble(const std::string& text);
// "%g" of a double, for default texts.
std::string FormatDouble(double value);

}  // namespace localizer
