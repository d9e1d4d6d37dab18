// Plural: "1 thread", never "1 threads".
#include "lf/core/plural.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

TEST(PluralTest, OneIsSingularAndEveryOtherCountPlural) {
    EXPECT_EQ(Plural(1, "thread"), "1 thread");
    EXPECT_EQ(Plural(2, "thread"), "2 threads");
    EXPECT_EQ(Plural(0, "task"), "0 tasks");
    EXPECT_EQ(Plural(-1, "job"), "-1 jobs");
    EXPECT_EQ(Plural(1, "pass"), "1 pass");
    EXPECT_EQ(Plural(4, "pass"), "4 passes");
    EXPECT_EQ(Plural(3, "patch"), "3 patches");
    EXPECT_EQ(Plural(int64_t(1) << 40, "sample"), "1099511627776 samples");
}

}  // namespace
}  // namespace lf
