// The shared Monaco package (fixture bake.monaco_geofabrik), opened once per
// test binary; a test using it names FIXTURES monaco_package.
#pragma once
#include <stdexcept>
#include <string>

#include "stream/city.h"

namespace blvd::test {

inline const stream::City& monacoCity() {
  static const stream::City* city = [] {
    auto* c = new stream::City;
    std::string err;
    if (c->open(BLVD_TEST_PACKAGE, err) != core::Status::Ok) throw std::runtime_error(err);
    return c;
  }();
  return *city;
}

}  // namespace blvd::test
