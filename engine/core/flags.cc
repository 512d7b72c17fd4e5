#include "engine/core/flags.h"

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>

namespace localizer {

StatusOr<int64_t> ParseInteger(const std::string& text) {
  int64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end) {
    return InvalidArgument("\"" + text + "\" is not an integer");
  }
  return value;
}

StatusOr<double> ParseFiniteDouble(const std::string& text) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(value)) {
    return InvalidArgument("\"" + text + "\" is not a finite number");
  }
  return value;
}

std::string FormatDouble(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

namespace {

StatusOr<int> ParseInt(const std::string& text) {
  auto value = ParseInteger(text);
  if (!value.ok()) return value.status();
  if (*value < INT_MIN || *value > INT_MAX) return InvalidArgument(text + " is out of range");
  return static_cast<int>(*value);
}

std::string WithUnit(const std::string& value, const std::string& unit) {
  return unit.empty() ? value : value + " " + unit;
}

}  // namespace

FlagSet::FlagSet(std::string usage, std::string summary) : usage_(std::move(usage)), summary_(std::move(summary)) {}

FlagSet::Flag& FlagSet::Add(FlagText text, std::function<Status(const std::string&)> set) {
  Flag flag;
  flag.name = std::move(text.name);
  flag.metavar = std::move(text.metavar);
  flag.help = std::move(text.help);
  flag.default_text = std::move(text.default_text);
  flag.set = std::move(set);
  flags_.push_back(std::move(flag));
  return flags_.back();
}

FlagSet::Flag& FlagSet::String(const std::string& name, std::string* value, const std::string& metavar,
                               const std::string& help) {
  return Add({name, metavar, help, value->empty() ? "" : *value}, [value](const std::string& text) {
    *value = text;
    return Status::Ok();
  });
}

FlagSet::Flag& FlagSet::Strings(const std::string& name, std::vector<std::string>* values, const std::string& metavar,
                                const std::string& help) {
  Flag& flag = Add({name, metavar, help, ""}, [values](const std::string& text) {
    values->push_back(text);
    return Status::Ok();
  });
  flag.repeatable = true;
  return flag;
}

FlagSet::Flag& FlagSet::Int(const std::string& name, int* value, const std::string& metavar, const std::string& unit,
                            const std::string& help) {
  return Add({name, metavar, help, WithUnit(std::to_string(*value), unit)}, [value](const std::string& text) -> Status {
    auto parsed = ParseInt(text);
    if (!parsed.ok()) return parsed.status();
    *value = *parsed;
    return Status::Ok();
  });
}

FlagSet::Flag& FlagSet::Uint64(const std::string& name, uint64_t* value, const std::string& metavar,
                               const std::string& help) {
  return Add({name, metavar, help, std::to_string(*value)}, [value](const std::string& text) -> Status {
    uint64_t parsed = 0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, parsed);
    if (text.empty() || ec != std::errc() || ptr != end) {
      return InvalidArgument("\"" + text + "\" is not a non-negative integer");
    }
    *value = parsed;
    return Status::Ok();
  });
}

FlagSet::Flag& FlagSet::Double(const std::string& name, double* value, const std::string& metavar,
                               const std::string& unit, const std::string& help) {
  return Add({name, metavar, help, WithUnit(FormatDouble(*value), unit)}, [value](const std::string& text) -> Status {
    auto parsed = ParseFiniteDouble(text);
    if (!parsed.ok()) return parsed.status();
    *value = *parsed;
    return Status::Ok();
  });
}

FlagSet::Flag& FlagSet::OptionalDouble(const std::string& name, std::optional<double>* value,
                                       const std::string& metavar, const std::string& default_text,
                                       const std::string& help) {
  return Add({name, metavar, help, default_text}, [value](const std::string& text) -> Status {
    auto parsed = ParseFiniteDouble(text);
    if (!parsed.ok()) return parsed.status();
    *value = *parsed;
    return Status::Ok();
  });
}

FlagSet::Flag& FlagSet::OptionalInt(const std::string& name, std::optional<int>* value, const std::string& metavar,
                                    const std::string& default_text, const std::string& help) {
  return Add({name, metavar, help, default_text}, [value](const std::string& text) -> Status {
    auto parsed = ParseInt(text);
    if (!parsed.ok()) return parsed.status();
    *value = *parsed;
    return Status::Ok();
  });
}

FlagSet::Flag& FlagSet::Bool(const std::string& name, bool* value, const std::string& help) {
  return Add({name, "", help, ""}, [value](const std::string&) {
    *value = true;
    return Status::Ok();
  });
}

FlagSet::Flag* FlagSet::Find(const std::string& name) {
  for (Flag& flag : flags_) {
    if (flag.name == name) return &flag;
  }
  return nullptr;
}

bool FlagSet::seen(const std::string& name) const {
  for (const Flag& flag : flags_) {
    if (flag.name == name) return flag.seen;
  }
  return false;
}

Status FlagSet::Parse(const std::vector<std::string>& args) {
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--help" || arg == "-h") {
      help_requested_ = true;
      return Status::Ok();
    }
    if (arg.size() < 3 || arg.compare(0, 2, "--") != 0) {
      return InvalidArgument("unexpected argument \"" + arg + "\" (flags start with --)");
    }
    const size_t equals = arg.find('=');
    const std::string name = arg.substr(2, equals == std::string::npos ? std::string::npos : equals - 2);
    Flag* flag = Find(name);
    if (flag == nullptr) return InvalidArgument("unknown flag --" + name);
    if (flag->seen && !flag->repeatable) return InvalidArgument("--" + name + " given twice");
    flag->seen = true;
    const bool is_bool = flag->metavar.empty();
    std::string value;
    if (equals != std::string::npos) {
      if (is_bool) return InvalidArgument("--" + name + " takes no value");
      value = arg.substr(equals + 1);
    } else if (!is_bool) {
      if (i + 1 >= args.size()) return InvalidArgument("--" + name + " needs a value " + flag->metavar);
      value = args[++i];
    }
    const Status status = flag->set(value);
    if (!status.ok()) return InvalidArgument("--" + name + ": " + status.message());
  }
  return CheckRequired();
}

Status FlagSet::CheckRequired() const {
  for (const Flag& flag : flags_) {
    if (flag.required && !flag.seen) return InvalidArgument("missing required flag --" + flag.name);
  }
  return Status::Ok();
}

namespace {

constexpr size_t kHelpColumn = 26;  // flag descriptions start here
constexpr size_t kLineWidth = 96;

// "  --name VALUE            description wrapped at kLineWidth, continued lines indented"
std::string FlagLine(const std::string& left, const std::string& description) {
  std::string text = left;
  if (text.size() < kHelpColumn) {
    text.resize(kHelpColumn, ' ');
  } else {
    text += "\n" + std::string(kHelpColumn, ' ');
  }
  size_t column = kHelpColumn;
  size_t start = 0;
  while (start < description.size()) {
    size_t end = description.find(' ', start);
    if (end == std::string::npos) end = description.size();
    const std::string word = description.substr(start, end - start);
    if (column > kHelpColumn && column + 1 + word.size() > kLineWidth) {
      text += "\n" + std::string(kHelpColumn, ' ');
      column = kHelpColumn;
    } else if (column > kHelpColumn) {
      text += ' ';
      ++column;
    }
    text += word;
    column += word.size();
    start = end + 1;
  }
  return text + "\n";
}

}  // namespace

std::string FlagSet::Usage() const {
  std::string text = "usage: " + usage_ + "\n\n" + summary_ + "\n\nflags:\n";
  for (const Flag& flag : flags_) {
    std::string description = flag.help;
    if (flag.required) description += " (required)";
    if (flag.repeatable) description += " (repeatable)";
    if (!flag.default_text.empty()) description += " (default: " + flag.default_text + ")";
    text += FlagLine("  --" + flag.name + (flag.metavar.empty() ? "" : " " + flag.metavar), description);
  }
  return text + FlagLine("  --help", "print this help");
}

}  // namespace localizer
