// FieldOf on a member without a row in its table must not compile (CTest
// field_of_needs_a_row); with FEMREG_LISTED the member has a row and the file compiles
// (field_of_finds_a_row), so the failure is the check's and not the file's.
#include "femreg/field_table.h"

namespace femreg {

struct TwoOptions {
  int listed = 0;
  int unlisted = 0;
};

template <>
struct OptionFields<TwoOptions> {
  static constexpr const char* kSection = "two";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    v(&TwoOptions::listed, FieldInfo("listed").AtLeast(0));
#ifdef FEMREG_LISTED
    v(&TwoOptions::unlisted, FieldInfo("unlisted"));
#endif
  }
};

static_assert(HasRow(&TwoOptions::listed));
static_assert(FieldOf<&TwoOptions::listed>().has_min);

const char* UnlistedKey() { return FieldOf<&TwoOptions::unlisted>().key; }

}  // namespace femreg
