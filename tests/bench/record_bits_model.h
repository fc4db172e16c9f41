// The model the record-bit measurements run on: PMSTREAM_RECORD_BITS_PMS=FILE.pms if set, else bunny built
// here. `measure(name, model)` runs on it; the test skips when neither is there.
#pragma once
#include <gtest/gtest.h>

#include <cstdlib>

#include "builder/build.h"
#include "io/mesh.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "test_support.h"

#define PMS_MEASURE_RECORD_BITS_MODEL(measure) PMS_MEASURE_RECORD_BITS_MODEL_BUILT(measure, ::pms::BuildOptions{})

// The same with the bunny built with `options` (the file, when given, is measured as it is).
#define PMS_MEASURE_RECORD_BITS_MODEL_BUILT(measure, options)                        \
  if (const char* path = std::getenv("PMSTREAM_RECORD_BITS_PMS")) {                  \
    const auto file = ::pms::PmsFile::open(path);                                    \
    measure(path, file->model());                                                    \
    return;                                                                          \
  }                                                                                  \
  PMS_REQUIRE_SHARED_MODEL(bunny_path, "bunny.ply.xz");                              \
  ::pms::Mesh mesh = ::pms::load_mesh(bunny_path.string());                          \
  ::pms::clean_mesh(mesh);                                                           \
  const ::pms::Hierarchy h = ::pms::build_progressive_mesh(mesh, options).hierarchy; \
  measure("bunny", ::pms::model_of(h))
