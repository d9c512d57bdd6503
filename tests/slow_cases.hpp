// A unit test's costly cases run in its slow ctest entry only
// (drape_add_slow_entry in cmake/DrapeTesting.cmake sets DRAPE_TEST_SLOW=1);
// the unit entry skips them and says which entry runs them.
#pragma once

#include <QtGlobal>

namespace drape_test {

inline bool slow_cases_enabled()
{
    return qEnvironmentVariableIsSet("DRAPE_TEST_SLOW");
}

} // namespace drape_test
