// A job's derived outputs beside its EXR frames: an 8-bit preview PNG per
// frame through OpenColorIO, the video encoded as frames become final, and
// relMSE against the job's reference image.
//
// Restart safety of the video: an encoder cannot be resumed after kill -9
// (its partial file has no trailer and dies with the process), so every run
// opens a fresh encoder and, before the first live frame, catches up by
// re-encoding the frames that an earlier run already made final from their
// EXRs on disk. Frames are fed strictly in the job's frame order, so the
// finished video holds every frame once, in order, whether or not the job was
// interrupted; an uninterrupted run encodes purely as frames stream in.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/io/color_transform.h"
#include "core/io/video_encoder.h"
#include "core/job/job_spec.h"
#include "core/util/status.h"

namespace gdvr::server {

std::string preview_file_name(int frame);  // "preview_0001.png"
// "video.mp4" | "video.mov" | "video.mkv"; "" for codec "none".
std::string video_file_name(const std::string& codec);

// Where the job's reference image for `frame` lives: `reference` may carry a
// printf pattern such as "%04d" for sequences; relative paths are under the
// asset root.
std::string reference_path(const std::string& asset_root, const std::string& reference, int frame);

// The main RGB image of a frame: the unnamed layer, else the first layer with
// three or more channels; nullptr when there is none.
const Image* main_rgb(const LayeredImage& image);

class JobOutputs {
 public:
  // Checks the output options (codec, OCIO config/display/view) and the
  // reference without rendering: errors name the field.
  static Status validate(const JobSpec& job, const std::string& ocio_config, const std::string& asset_root,
                         int first_frame);

  // `frames`: the job's whole range in order; `dir`: its output folder, which
  // holds frame_NNNN.exr for frames an earlier run finished.
  static Expected<std::unique_ptr<JobOutputs>> open(const JobSpec& job, std::vector<int> frames, std::string dir,
                                                    const std::string& ocio_config, std::string asset_root);
  ~JobOutputs();

  // Before the frame is announced: computes the display image, writes the
  // preview (atomically) and, when the job has a reference, fills `*errors`
  // with both relMSE forms of core/report/error_metrics.h (the figures
  // gdvr-report uses); `left_out` says why they are missing. The display image
  // is kept for add_to_video().
  struct FrameErrors {
    double rel_mse = -1;         // per-pixel form; -1: no reference
    double rel_mse_global = -1;  // global form; -1: no reference
  };
  Status prepare_frame(int frame, const LayeredImage& image, FrameErrors* errors, std::vector<std::string>* left_out);
  // After the frame is announced: appends it to the video, first re-encoding
  // any earlier frame of the range not yet in it from its EXR.
  Status add_to_video(int frame);
  // At completion: encodes what is still missing and moves the video into
  // place. Returns its file name ("" without video).
  Expected<std::string> finish();

  int64_t video_frames() const;

 private:
  JobOutputs() = default;
  Status encode(const Image& display);
  Status catch_up_before(int frame);

  JobSpec job_;
  std::vector<int> frames_;
  std::string dir_, asset_root_;
  std::unique_ptr<ColorTransform> transform_;
  std::unique_ptr<VideoEncoder> video_;
  std::string video_name_;
  size_t next_video_index_ = 0;  // into frames_: the next frame the video needs
  int pending_frame_ = -1;       // frame whose display image is held
  Image pending_display_;
  std::unique_ptr<Image> reference_;  // single (non-sequence) reference, loaded once
};

// Removes partial files a killed server left in a job folder (core's atomic
// writers name them "<file>.tmp.<pid>", the server's own "<file>.tmp"): only
// one run of a job exists at a time, so none of them can still be in use.
void remove_stale_temporaries(const std::string& dir);

}  // namespace gdvr::server
