// femreg/field_table.h - the machinery of the options' field tables, each option described
// once.
//
// OptionFields<S>::Visit(v) calls v(&S::member, FieldInfo) for every member of the options
// struct S that the table describes, in the order the scene file writes them (constexpr, so
// that FieldOf refuses a member without a row when it compiles). The scene
// parser and writer, the range checks of S::IsValid, the Python module and a run's
// provenance all walk the table, so an option is named in its struct and in its table row
// and nowhere else (docs/dev/adding-an-option.md). A field's type says how it is read and
// written: bool, an integer, double, Eigen::Vector3d (a list of 3), or an enum with
// EnumValues (written as ToString's names); or std::optional of one of them, a value a scene
// may leave unset (a pair's own friction, forward.model): unset, it is neither written nor
// range-checked, and Python and the provenance show it as None / null.
//
// The tables sit beside their structs: the registration's in femreg/option_fields.h, the
// material's in femreg/fem.h, the forward solve's in femreg/forward.h, collision's in
// femreg/collision_spec.h, fracture's in femreg/fracture.h, the virtual sensor's in
// femreg/synth.h and synth's in femreg/scene.h. This header depends on nothing of femreg, so
// each module can describe its own options.
#ifndef FEMREG_FIELD_TABLE_H_
#define FEMREG_FIELD_TABLE_H_

#include <Eigen/Core>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>

namespace femreg {

// Whether a field's type is std::optional (a value a scene may leave unset), and the type of
// its value either way.
template <class T>
struct FieldType {
  static constexpr bool kOptional = false;
  using Value = T;
};
template <class T>
struct FieldType<std::optional<T>> {
  static constexpr bool kOptional = true;
  using Value = T;
};

// One field: its scene key (also the key in provenance and in messages, "weights.elastic"),
// its Python attribute where that differs, a docstring for Python, and the range IsValid
// holds a number to. A number with a bound must also be finite.
struct FieldInfo {
  const char* key = "";
  const char* python = nullptr;  // nullptr: the Python attribute is the key
  const char* doc = "";
  bool finite = false;
  bool has_min = false, min_open = false, has_max = false, max_open = false;
  double min = 0.0, max = 0.0;
  const char* note = nullptr;  // follows the range in the message: "must be >= 0 (0 = off)"
  // A field nested one level down in its section (`outliers: {neighbors: 8}`): the group's
  // key; its own key is then the one inside the group. Null: directly in the section.
  const char* group = nullptr;
  bool required = false;  // in a group: written whenever the group is (a plane's distance)
  // A flag that is its group's presence (FieldInfo::key names the group): set when the section
  // has the group, and the group is written in full when it is set (synth's background).
  bool switch_of_group = false;
  // Written after the entries its section writes by hand (an object's toughness after its
  // material), so that a written scene keeps the order of the hand-written ones.
  bool after = false;

  constexpr explicit FieldInfo(const char* k) : key(k) {}
  constexpr FieldInfo AtLeast(double v) const { return Bound(true, v, false); }
  constexpr FieldInfo Above(double v) const { return Bound(true, v, true); }
  constexpr FieldInfo AtMost(double v) const { return Bound(false, v, false); }
  constexpr FieldInfo Below(double v) const { return Bound(false, v, true); }
  constexpr FieldInfo Finite() const { return With(&FieldInfo::finite, true); }
  constexpr FieldInfo Note(const char* n) const { return With(&FieldInfo::note, n); }
  constexpr FieldInfo In(const char* g) const { return With(&FieldInfo::group, g); }
  constexpr FieldInfo Required() const { return With(&FieldInfo::required, true); }
  constexpr FieldInfo SwitchesGroup() const { return With(&FieldInfo::switch_of_group, true); }
  constexpr FieldInfo After() const { return With(&FieldInfo::after, true); }
  constexpr FieldInfo Python(const char* name) const { return With(&FieldInfo::python, name); }
  constexpr FieldInfo Doc(const char* d) const { return With(&FieldInfo::doc, d); }
  const char* python_name() const { return python != nullptr ? python : key; }
  // The key within the section: "outliers.neighbors", or the key.
  std::string path() const { return group != nullptr ? std::string(group) + "." + key : std::string(key); }
  bool checked() const { return finite || has_min || has_max; }
  // Whether a number lies in the range (NaN never does; nor infinity when checked).
  bool InRange(double v) const {
    if (std::isnan(v) || (finite && !std::isfinite(v))) return false;
    if (has_min && (min_open ? !(v > min) : !(v >= min))) return false;
    if (has_max && (max_open ? !(v < max) : !(v <= max))) return false;
    return true;
  }
  // "must be >= 0 (0 = off)", "must be in (0, 1)", "must be finite".
  std::string RangeMessage() const {
    std::ostringstream os;
    os << "must be ";
    if (has_min && has_max) {
      os << "in " << (min_open ? "(" : "[") << min << ", " << max << (max_open ? ")" : "]");
    } else if (has_min) {
      os << (min_open ? "> " : ">= ") << min;
    } else if (has_max) {
      os << (max_open ? "< " : "<= ") << max;
    } else {
      os << "finite";
    }
    if (note != nullptr) os << " " << note;
    return os.str();
  }
  // RangeMessage and the value: "must be >= 0 (0 = off) (got -1)".
  template <class T>
  std::string RangeError(const T& value) const {
    std::ostringstream os;
    os << RangeMessage() << " (got " << value << ")";
    return os.str();
  }

 private:
  // A copy with one member set: the builders above.
  template <class T>
  constexpr FieldInfo With(T FieldInfo::*member, T value) const {
    FieldInfo f = *this;
    f.*member = value;
    return f;
  }
  constexpr FieldInfo Bound(bool lower, double v, bool open) const {
    FieldInfo f = *this;
    f.finite = true;
    if (lower) {
      f.has_min = true, f.min = v, f.min_open = open;
    } else {
      f.has_max = true, f.max = v, f.max_open = open;
    }
    return f;
  }
};

// An enum's values in the order messages list them; FromString accepts exactly their
// ToString names. Specialized beside each enum a table holds.
template <class Enum>
struct EnumValues;

// The tables. kSection is the struct's key path in the scene file ("weights",
// "effects.fracture"; "" for the registration's top level and a material) and names its
// fields in messages.
template <class Options>
struct OptionFields;

// A field as messages name it: "weights.elastic"; "loads" at the top level.
template <class Options>
std::string FieldName(const FieldInfo& f) {
  const std::string section = OptionFields<Options>::kSection;
  return section.empty() ? f.path() : section + "." + f.path();
}

// The struct and the type of a pointer to one of its members.
template <class M>
struct MemberPointer;
template <class C, class T>
struct MemberPointer<T C::*> {
  using Class = C;
  using Field = T;
};

// Whether `member` has a row in its struct's table; a constant expression (the tables'
// Visit are constexpr), so that FieldOf refuses a member without a row when it compiles.
template <class Options, class T>
constexpr bool HasRow(T Options::*member) {
  bool found = false;
  OptionFields<Options>::Visit([&](auto m, const FieldInfo&) {
    if constexpr (std::is_same_v<decltype(m), T Options::*>) found = found || m == member;
  });
  return found;
}

// The row of one member in its struct's table (a key the section also reads elsewhere: a
// region's toughness is the object's row): FieldOf<&ObjectSpec::toughness>(). A member
// without a row does not compile.
template <auto kMember>
constexpr FieldInfo FieldOf() {
  using Options = typename MemberPointer<decltype(kMember)>::Class;
  static_assert(HasRow(kMember), "FieldOf: this member has no row in its struct's OptionFields table");
  FieldInfo row("");
  OptionFields<Options>::Visit([&](auto m, const FieldInfo& f) {
    if constexpr (std::is_same_v<decltype(m), decltype(kMember)>) {
      if (m == kMember) row = f;
    }
  });
  return row;
}

// The first number of `o` out of its table row's range, as "section.key message (got
// value)" in *error (IsValid's form); true when every field is in range.
template <class Options>
bool CheckFieldRanges(const Options& o, std::string* error) {
  bool ok = true;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    using Field = std::decay_t<decltype(o.*member)>;
    using T = typename FieldType<Field>::Value;
    if (!ok || !f.checked()) return;
    const T* value = nullptr;
    if constexpr (FieldType<Field>::kOptional) {
      if (!(o.*member).has_value()) return;  // unset: nothing to check
      value = &*(o.*member);
    } else {
      value = &(o.*member);
    }
    if constexpr (std::is_same_v<T, Eigen::Vector3d>) {  // finite only
      if (value->allFinite()) return;
      ok = false;
      if (error != nullptr) {
        std::ostringstream os;
        os << FieldName<Options>(f) << " " << f.RangeMessage() << " (got [" << value->x() << ", "
           << value->y() << ", " << value->z() << "])";
        *error = os.str();
      }
    } else if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      if (f.InRange(static_cast<double>(*value))) return;
      ok = false;
      if (error != nullptr) {
        std::ostringstream os;
        os << FieldName<Options>(f) << " " << f.RangeMessage() << " (got " << *value << ")";
        *error = os.str();
      }
    }
  });
  return ok;
}

}  // namespace femreg

#endif  // FEMREG_FIELD_TABLE_H_
