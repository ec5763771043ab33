// The one output stage of a job, shared by every front end (gdvr-render,
// gdvr-farm finalize, gdvr-server): the file names, the EXR of each final
// frame, an 8-bit preview PNG per frame through OpenColorIO, the video
// encoded as frames become final, relMSE against the job's reference image,
// and stats.json. The same job gives the same folder whichever front end runs
// it (tests/tools/output_stage_test.py).
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
#include "core/io/image_io.h"
#include "core/io/video_encoder.h"
#include "core/job/job_runner.h"
#include "core/job/job_spec.h"
#include "core/util/status.h"

namespace gdvr {

std::string frame_file_name(int frame);    // "frame_0001.exr"
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

// Every named EXR layer an integrator can put into a final frame (the
// unnamed layer, the image itself, is always written): what
// job.outputs.exr_layers may select from.
const std::vector<std::string>& known_exr_layers();

// The codec of the job's EXR frames: job.outputs.exr_compression, with
// "auto" resolved (RLE under a time budget, ZIP otherwise).
ExrCompression frame_exr_compression(const JobSpec& job);

// A final frame as written: its file and what it cost, with the figures the
// output stage adds (relMSE against the reference, the shift failure rate).
struct WrittenFrame {
  std::string file;  // "frame_0001.exr", in the output folder
  uint64_t bytes = 0;
  FrameStats stats;
};

// One frame's entry of stats.json as compact JSON, and back. gdvr-farm keeps
// one per finalized frame beside its buffers, so whichever finalize task runs
// last can list every frame of the job, not just its own.
std::string frame_entry_json(const WrittenFrame& frame);
Expected<WrittenFrame> parse_frame_entry(const std::string& json_text);

// stats.json: the job's frames in frame order with their statistics and the
// totals. `header` holds what only the caller knows ("job_id", "state",
// "error"; may be empty), written first.
std::string stats_json(const std::vector<std::pair<std::string, std::string>>& header, int frames_total,
                       const std::vector<WrittenFrame>& frames);

class JobOutputs {
 public:
  // `ocio_config`: "" for $OCIO or gdvr's shipped config. `asset_root`: where
  // a relative reference path is found.
  struct Options {
    std::string ocio_config;
    std::string asset_root;
  };

  // Checks the output options (layers, codec, OCIO config/display/view) and
  // the reference without rendering: errors name the field.
  static Status validate(const JobSpec& job, const Options& options, int first_frame);

  // `frames`: the frames this run is responsible for, in order (the video
  // holds exactly these); `dir`: the output folder, which may hold
  // frame_NNNN.exr for frames an earlier run finished.
  static Expected<std::unique_ptr<JobOutputs>> open(const JobSpec& job, std::vector<int> frames, std::string dir,
                                                    Options options);
  ~JobOutputs();

  // Before the frame is announced: writes its EXR (atomically; the image and
  // the layers job.outputs.exr_layers selects, all when it is empty; a selected
  // layer this integrator does not produce is named in left_out), computes the
  // display image, writes the preview and, when the job has a reference,
  // fills the record's relMSE with both forms of core/image/error_metrics.h
  // (the figures gdvr-report uses); the record's left_out says why they are
  // missing. The display image is kept for add_to_video().
  Expected<WrittenFrame> write_frame(const FrameOutput& frame);
  // A frame an earlier run already wrote: writes its preview if that is
  // missing (a run killed between the two), from the EXR on disk.
  Status complete_earlier_frame(int frame);
  // After the frame is announced: appends it to the video, first re-encoding
  // any earlier frame of the range not yet in it from its EXR.
  Status add_to_video(int frame);
  // At completion: encodes what is still missing and moves the video into
  // place. Returns its file name ("" without video).
  Expected<std::string> finish();
  // For a time budget, before any frame is final (JobCallbacks::
  // estimate_frame_final_seconds): about what write_frame will take for a
  // frame of these layers, timed by writing them as an EXR to a temporary file
  // in the folder (removed again; a stale one is a temporary as any other).
  // Previews, relMSE and video are not in it. 0 if it cannot be written.
  double estimate_write_seconds(const LayeredImage& layers) const;

  int64_t video_frames() const;

 private:
  JobOutputs() = default;
  Status encode(const Image& display);
  LayeredImage selected_layers(const LayeredImage& image, std::vector<std::string>* left_out) const;
  Status catch_up_before(int frame);
  Expected<Image> display_from_disk(int frame);

  JobSpec job_;
  std::vector<int> frames_;
  std::string dir_;
  Options options_;
  std::unique_ptr<ColorTransform> transform_;
  std::unique_ptr<VideoEncoder> video_;
  std::string video_name_;
  size_t next_video_index_ = 0;  // into frames_: the next frame the video needs
  int pending_frame_ = -1;       // frame whose display image is held
  Image pending_display_;
  std::unique_ptr<Image> reference_;  // single (non-sequence) reference, loaded once
};

// Removes partial files a killed run left in a job folder (core's atomic
// writers name them "<file>.tmp.<host>.<pid>", the server's own "<file>.tmp"):
// call it only where a single run of the job can exist at a time.
void remove_stale_temporaries(const std::string& dir);

}  // namespace gdvr
