// Table-driven refusal tests: a component's Configure must refuse each listed change to its
// default options, every change applied alone.
#pragma once

#include <gtest/gtest.h>

#include <initializer_list>

#include "swf/core/status.hpp"

namespace swf::testing {

// For each change: a fresh Component, default Options with only that change, and Configure must
// answer kInvalidArgument (a failure names the change by its index in the list).
template <typename Component, typename Options>
void ExpectEachRefused(std::initializer_list<void (*)(Options&)> changes) {
  int index = 0;
  for (const auto change : changes) {
    Component component;
    Options options;
    change(options);
    EXPECT_EQ(component.Configure(options), core::Status::kInvalidArgument) << "change " << index;
    ++index;
  }
}

}  // namespace swf::testing
