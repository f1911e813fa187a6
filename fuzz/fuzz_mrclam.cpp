// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the MRCLAM parser and importer (dataset/mrclam.hpp), as
// mrclam_import runs them: Dataset::load of a directory's five files for robot 1,
// then FrameSource (frame times, odometry integration, observation binning) and
// every frame. An input is a sequence of records (fuzz_input.hpp) whose channel
// picks the file they are appended to: Barcodes.dat, Landmark_Groundtruth.dat,
// Robot1_Odometry.dat, Robot1_Groundtruth.dat, Robot1_Measurement.dat. A bad
// dataset must end in DatasetError or std::invalid_argument (the importer's exit
// 2), never in another exception or a crash.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "elaslam/dataset/mrclam.hpp"
#include "fuzz_input.hpp"

namespace {

using namespace elaslam;

const char* const kFiles[] = {"Barcodes.dat", "Landmark_Groundtruth.dat", "Robot1_Odometry.dat",
                              "Robot1_Groundtruth.dat", "Robot1_Measurement.dat"};

// A directory of its own under TMPDIR (tools/fuzz.sh points it at tmpfs), removed at exit.
struct WorkDir {
  WorkDir() {
    path = (std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") + std::string("/elaslam_fuzz_XXXXXX");
    if (!mkdtemp(path.data())) std::abort();
  }
  ~WorkDir() {
    for (const char* f : kFiles) std::remove((path + "/" + f).c_str());
    rmdir(path.c_str());
  }
  std::string path;
};

const std::string& work_dir() {
  static const WorkDir dir;
  return dir.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text[std::size(kFiles)];
  fuzz::for_each_record(data, size, std::size(kFiles), [&](const fuzz::Record& r) {
    text[r.channel].append(reinterpret_cast<const char*>(r.data), r.size);
  });
  for (std::size_t i = 0; i < std::size(kFiles); ++i) {
    std::FILE* f = std::fopen((work_dir() + "/" + kFiles[i]).c_str(), "wb");
    if (!f) std::abort();
    std::fwrite(text[i].data(), 1, text[i].size(), f);
    std::fclose(f);
  }
  try {
    const mrclam::Dataset d = mrclam::Dataset::load(work_dir(), {1});
    mrclam::Options o;
    o.robots = {1};
    const mrclam::FrameSource src(d, o);
    ground_truth_t gt;
    std::vector<sensor_frame_t> sensors;
    for (int k = 0; k < src.num_frames() && k < 100000; ++k) src.frame(k, &gt, &sensors);
  } catch (const mrclam::DatasetError&) {
  } catch (const std::invalid_argument&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_mrclam: an unexpected exception escaped: %s\n", e.what());
    std::abort();
  }
  return 0;
}
