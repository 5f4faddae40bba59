// The version macros (generated from project(VERSION)) and normalflow::version() agree.
#include <gtest/gtest.h>

#include <string>

#include "core/version.h"

TEST(Version, MacrosAndFunctionAgree) {
    EXPECT_EQ(std::string(normalflow::version()), NORMALFLOW_VERSION_STRING);
    EXPECT_EQ(std::string(NORMALFLOW_VERSION_STRING), std::to_string(NORMALFLOW_VERSION_MAJOR) + "." +
                                                          std::to_string(NORMALFLOW_VERSION_MINOR) + "." +
                                                          std::to_string(NORMALFLOW_VERSION_PATCH));
    EXPECT_EQ(NORMALFLOW_VERSION,
              NORMALFLOW_VERSION_MAJOR * 10000 + NORMALFLOW_VERSION_MINOR * 100 + NORMALFLOW_VERSION_PATCH);
}
