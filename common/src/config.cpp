// SPDX-License-Identifier: Apache-2.0
#include "elaslam/common/config.hpp"

#include "config_input.hpp"

#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <type_traits>

namespace elaslam::config {
namespace {

std::string join_lines(const std::string& source, const std::vector<std::string>& problems) {
  std::ostringstream os;
  os << source << ": " << problems.size() << " configuration problem" << (problems.size() == 1 ? "" : "s")
     << ":";
  for (const auto& p : problems) os << "\n  " << p;
  return os.str();
}

std::string scalar_text(const YAML::Node& n) {
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "nothing";
}

/// A map key as text, also when it is not a scalar (from_string refuses those; a
/// Reader built on another node must not throw YAML::TypedBadConversion).
std::string key_text(const YAML::Node& key) {
  return key.IsScalar() ? key.Scalar() : "<" + scalar_text(key) + " as a key>";
}

/// True when `text` is all a number that is not finite ("nan", "-inf", "1e999").
bool non_finite_text(const std::string& text) {
  if (text.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && !std::isfinite(v);
}

template <typename T>
std::string num(T v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

bool is_one_of(const std::string& v, std::initializer_list<const char*> allowed) {
  return std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return v == a; });
}

/// The problem with value `v` when it is not one of `allowed` ("" when it is).
std::string not_one_of(const std::string& v, std::initializer_list<const char*> allowed) {
  if (is_one_of(v, allowed)) return "";
  std::string list;
  for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
  return "invalid value '" + v + "', expected one of: " + list;
}

/// The problem with a list of n items when n is outside [lo, hi] ("" when inside).
std::string length_problem(std::size_t n, std::size_t lo, std::size_t hi) {
  if (n >= lo && n <= hi) return "";
  return "wrong length: got " + num(n) + " items, expected " + num(lo) + " to " + num(hi);
}

/// "" when `n` is a list of lo..hi items, else what is wrong: not a list (`what`
/// says what was expected), or its length.
std::string list_problem(const YAML::Node& n, const char* what, std::size_t lo, std::size_t hi) {
  if (!n.IsSequence()) return std::string("wrong type: expected ") + what + ", got " + scalar_text(n);
  return length_problem(n.size(), lo, hi);
}

}  // namespace

ConfigError::ConfigError(const std::string& source, std::vector<std::string> problems)
    : std::runtime_error(join_lines(source, problems)), problems_(std::move(problems)) {}

ConfigError::ConfigError(std::string message, std::vector<std::string> problems, int)
    : std::runtime_error(std::move(message)), problems_(std::move(problems)) {}

ConfigError ConfigError::not_found(const std::string& headline, std::vector<std::string> places) {
  std::string message = headline;
  for (const auto& p : places) message += "\n  " + p;
  return ConfigError(std::move(message), std::move(places), 0);
}

Reader::Reader(YAML::Node node, std::string path, std::shared_ptr<ParseState> state)
    : node_(std::move(node)), path_(std::move(path)), state_(std::move(state)) {
  // Locate (creating) this map in the effective config.
  effective_.reset(state_->effective);
  if (!path_.empty()) {
    std::stringstream ss(path_);
    std::string part;
    while (std::getline(ss, part, '.')) {
      YAML::Node next = effective_[part];
      if (!next.IsMap()) {
        effective_[part] = YAML::Node(YAML::NodeType::Map);
        next = effective_[part];
      }
      effective_.reset(next);
    }
  }
}

Reader::Reader(YAML::Node node, std::string path, std::shared_ptr<ParseState> state, YAML::Node effective)
    : node_(std::move(node)), path_(std::move(path)), state_(std::move(state)) {
  effective_.reset(effective);
}

std::string Reader::key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

bool Reader::has(const std::string& key) const {
  const YAML::Node& n = node_;
  return n.IsMap() && n[key].IsDefined() && !n[key].IsNull();
}

void Reader::fail(const std::string& key, const std::string& what) {
  state_->problems.push_back(key_path(key) + ": " + what);
}

YAML::Node Reader::child(const std::string& key, bool optional, bool* present) {
  *present = false;
  if (std::find(seen_.begin(), seen_.end(), key) == seen_.end()) seen_.push_back(key);
  if (!node_.IsMap()) return YAML::Node();
  const YAML::Node& const_node = node_;  // const access: never inserts the key
  YAML::Node n = const_node[key];
  if (!n.IsDefined() || n.IsNull()) {
    if (!optional) fail(key, "missing (required key)");
    return YAML::Node();
  }
  *present = true;
  return n;
}

void Reader::record(const std::string& key, const YAML::Node& value) { effective_[key] = value; }

template <typename T>
bool Reader::scalar(const std::string& key, T* out, bool optional, const char* type_name) {
  bool present = false;
  YAML::Node n = child(key, optional, &present);
  if (!present) {
    if (optional) record(key, YAML::Node(*out));
    return false;
  }
  if (!n.IsScalar()) {
    fail(key, std::string("wrong type: expected ") + type_name + ", got " + scalar_text(n));
    return false;
  }
  try {
    *out = n.as<T>();
  } catch (const YAML::Exception&) {
    if constexpr (std::is_floating_point_v<T>) {
      if (non_finite_text(n.Scalar())) {  // nan, inf, 1e999: C's spellings, not YAML's .nan and .inf
        fail(key, "not a finite number: got " + scalar_text(n));
        return false;
      }
    }
    fail(key, std::string("wrong type: expected ") + type_name + ", got " + scalar_text(n));
    return false;
  }
  record(key, YAML::Node(*out));
  return true;
}

void Reader::check_range(const std::string& key, double v, double lo, double hi) {
  const std::string range = "a value in [" + num(lo) + ", " + num(hi) + "]";
  if (!std::isfinite(v))  // .nan passes every comparison test, .inf any open bound
    fail(key, "not a finite number: got " + num(v) + ", expected " + range);
  else if (!(v >= lo && v <= hi))
    fail(key, "out of range: got " + num(v) + ", expected " + range);
}

void Reader::read(const std::string& key, double* out, double lo, double hi) {
  if (scalar(key, out, false, "a number")) check_range(key, *out, lo, hi);
}
void Reader::read_optional(const std::string& key, double* out, double lo, double hi) {
  if (scalar(key, out, true, "a number")) check_range(key, *out, lo, hi);
}
void Reader::read(const std::string& key, int* out, int lo, int hi) {
  if (scalar(key, out, false, "an integer") && !(*out >= lo && *out <= hi))
    fail(key, "out of range: got " + num(*out) + ", expected an integer in [" + num(lo) + ", " + num(hi) + "]");
}
void Reader::read_optional(const std::string& key, int* out, int lo, int hi) {
  if (scalar(key, out, true, "an integer") && !(*out >= lo && *out <= hi))
    fail(key, "out of range: got " + num(*out) + ", expected an integer in [" + num(lo) + ", " + num(hi) + "]");
}
void Reader::read(const std::string& key, bool* out) { scalar(key, out, false, "true or false"); }
void Reader::read_optional(const std::string& key, bool* out) { scalar(key, out, true, "true or false"); }
void Reader::read(const std::string& key, std::string* out) { scalar(key, out, false, "a string"); }
void Reader::read_optional(const std::string& key, std::string* out) { scalar(key, out, true, "a string"); }

void Reader::read_enum(const std::string& key, std::string* out, std::initializer_list<const char*> allowed,
                       bool optional) {
  if (!scalar(key, out, optional, "a string")) return;
  const std::string problem = not_one_of(*out, allowed);
  if (!problem.empty()) fail(key, problem);
}

void Reader::read_vector(const std::string& key, std::vector<double>* out, std::size_t size, double lo,
                         double hi) {
  bool present = false;
  YAML::Node n = child(key, false, &present);
  if (!present) return;
  if (!n.IsSequence() || n.size() != size) {
    fail(key, "wrong type: expected a list of " + num(size) + " numbers, got " +
                  (n.IsSequence() ? "a list of " + num(n.size()) : scalar_text(n)));
    return;
  }
  std::vector<double> v(size);
  for (std::size_t i = 0; i < size; ++i) {
    try {
      v[i] = n[i].as<double>();
    } catch (const YAML::Exception&) {
      const bool non_finite = n[i].IsScalar() && non_finite_text(n[i].Scalar());
      fail(key + "[" + num(i) + "]", (non_finite ? "not a finite number: got " : "wrong type: expected a number, got ") +
                                         scalar_text(n[i]));
      return;
    }
    check_range(key + "[" + num(i) + "]", v[i], lo, hi);
  }
  *out = v;
  YAML::Node rec(YAML::NodeType::Sequence);
  for (double d : v) rec.push_back(d);
  rec.SetStyle(YAML::EmitterStyle::Flow);
  record(key, rec);
}

void Reader::read_enum_list(const std::string& key, std::vector<std::string>* out,
                            std::initializer_list<const char*> allowed, std::size_t min_items,
                            std::size_t max_items, bool optional) {
  auto echo = [&](const std::vector<std::string>& items) {
    YAML::Node rec(YAML::NodeType::Sequence);
    for (const std::string& item : items) rec.push_back(item);
    rec.SetStyle(YAML::EmitterStyle::Flow);
    record(key, rec);
  };
  bool present = false;
  YAML::Node n = child(key, optional, &present);
  if (!present) {
    if (optional) echo(*out);
    return;
  }
  if (const std::string problem = list_problem(n, "a list of strings", min_items, max_items); !problem.empty()) {
    fail(key, problem);
    return;
  }
  std::vector<std::string> v;
  bool ok = true;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string item_key = key + "[" + num(i) + "]";
    if (!n[i].IsScalar()) {
      fail(item_key, "wrong type: expected a string, got " + scalar_text(n[i]));
      ok = false;
      continue;
    }
    const std::string item = n[i].Scalar();
    if (const std::string problem = not_one_of(item, allowed); !problem.empty()) {
      fail(item_key, problem);
      ok = false;
      continue;
    }
    v.push_back(item);
  }
  if (!ok) return;
  *out = v;
  echo(v);
}

void Reader::section(const std::string& key, const std::function<void(Reader&)>& fn, bool optional) {
  bool present = false;
  YAML::Node n = child(key, optional, &present);
  if (!present) return;
  if (!n.IsMap()) {
    fail(key, "wrong type: expected a map of keys, got " + scalar_text(n));
    return;
  }
  YAML::Node effective = effective_[key];
  if (!effective.IsMap()) {
    effective_[key] = YAML::Node(YAML::NodeType::Map);
    effective = effective_[key];
  }
  Reader sub(n, key_path(key), state_, effective);
  fn(sub);
  sub.finish();
}

void Reader::list(const std::string& key, const std::function<void(Reader&, std::size_t)>& fn,
                  std::size_t min_items, std::size_t max_items) {
  bool present = false;
  YAML::Node n = child(key, false, &present);
  if (!present) return;
  if (const std::string problem = list_problem(n, "a list", min_items, max_items); !problem.empty()) {
    fail(key, problem);
    return;
  }
  YAML::Node rec(YAML::NodeType::Sequence);
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string item_path = key_path(key) + "[" + num(i) + "]";
    if (!n[i].IsMap()) {
      state_->problems.push_back(item_path + ": wrong type: expected a map of keys, got " + scalar_text(n[i]));
      continue;
    }
    // Items get their own effective subtree (a list is not addressable by dotted path).
    auto item_state = std::make_shared<ParseState>();
    Reader sub(n[i], "", item_state);
    sub.path_ = item_path;
    fn(sub, i);
    sub.finish();
    for (auto& p : item_state->problems) state_->problems.push_back(std::move(p));
    rec.push_back(item_state->effective);
  }
  record(key, rec);
}

void Reader::finish() {
  if (!node_.IsMap()) return;
  for (const auto& kv : node_) {
    const std::string k = key_text(kv.first);
    if (std::find(seen_.begin(), seen_.end(), k) == seen_.end()) {
      std::string known;
      for (const auto& s : seen_) known += (known.empty() ? "" : ", ") + s;
      fail(k, "unknown key (known keys here: " + known + ")");
    }
  }
}

namespace {
/// Records where each document starts; ignores the rest (a counting pass).
class DocumentStarts final : public YAML::EventHandler {
 public:
  explicit DocumentStarts(std::vector<YAML::Mark>* starts) : starts_(starts) {}
  void OnDocumentStart(const YAML::Mark& mark) override { starts_->push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

 private:
  std::vector<YAML::Mark>* starts_;
};
}  // namespace

Document::Document(YAML::Node root, std::string source)
    : root_(std::move(root)), source_(std::move(source)), state_(std::make_shared<ParseState>()) {}

Document Document::from_string(const std::string& text, const std::string& source) {
  std::vector<std::string> problems = input::text_problems(text);
  if (!problems.empty()) throw ConfigError(source, problems);
  // Not YAML::LoadAll: in yaml-cpp 0.7 it loops forever, allocating, when the parser
  // keeps reporting a document it cannot read (jbeder/yaml-cpp#1319, fixed after 0.7;
  // fuzz_config found two such configs). The documents are counted by a pass that
  // stops at the second, and the first is built by YAML::Load.
  YAML::Node root;
  std::vector<YAML::Mark> starts;
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    DocumentStarts counter(&starts);
    while (starts.size() < 2 && parser.HandleNextDocument(counter)) {
    }
    if (starts.size() < 2) root = YAML::Load(text);
  } catch (const YAML::Exception& e) {  // ParserException, and DeepRecursion (nesting beyond yaml-cpp's bound)
    throw ConfigError(source, {"malformed YAML at line " + std::to_string(e.mark.line + 1) + ", column " +
                                   std::to_string(e.mark.column + 1) + ": " + e.msg});
  }
  if (starts.size() > 1) {
    const YAML::Mark m = starts[1];
    throw ConfigError(source, {"a second YAML document" +
                               (m.is_null() ? std::string() : " at line " + std::to_string(m.line + 1)) +
                               " (where its '---' or its content starts): a configuration is one document; merge the two or remove one"});
  }
  if (!root.IsMap())
    throw ConfigError(source, {"expected a map of sections at the top level, got " + scalar_text(root)});
  problems = input::structure_problems(root);
  if (!problems.empty()) throw ConfigError(source, problems);
  return Document(root, source);
}

Document Document::from_file(const std::string& path) {
  std::string text, why;
  if (!input::read_file(path, &text, &why)) throw ConfigError(path, {why});
  return from_string(text, path);
}

void Document::know(const std::string& key) {
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.push_back(key);
}

void Document::section(const std::string& key, const std::function<void(Reader&)>& fn, bool optional) {
  know(key);
  const YAML::Node& root = root_;
  YAML::Node n = root[key];
  if (!n.IsDefined() || n.IsNull()) {
    if (!optional) state_->problems.push_back(key + ": missing (required section)");
    return;
  }
  if (!n.IsMap()) {
    state_->problems.push_back(key + ": wrong type: expected a map of keys, got " + scalar_text(n));
    return;
  }
  Reader r(n, key, state_);
  fn(r);
  r.finish();
}

void Document::allow(std::initializer_list<const char*> keys) {
  for (const char* k : keys) know(k);
}

void Document::allow_sections() {
  for (const char* k : kSections) know(k);
}

void Document::finish() {
  for (const auto& kv : root_) {
    const std::string k = key_text(kv.first);
    if (std::find(known_.begin(), known_.end(), k) == known_.end()) {
      std::string known;
      for (const std::string& name : known_) known += (known.empty() ? "" : ", ") + name;
      state_->problems.push_back(k + ": unknown section (known sections: " + known + ")");
    }
  }
  if (!state_->problems.empty()) throw ConfigError(source_, state_->problems);
}

std::string Document::effective_yaml() const {
  YAML::Emitter out;
  out << state_->effective;
  return out.c_str();
}

std::string edit_yaml(const std::string& text, const std::function<void(YAML::Node& root)>& edit, bool create) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception&) {  // our own loader's output: not expected
  }
  if (!root.IsMap()) {
    if (!create) return text;
    root = YAML::Node(YAML::NodeType::Map);
  }
  edit(root);
  YAML::Emitter out;
  out << root;
  return out.c_str();
}

}  // namespace elaslam::config
