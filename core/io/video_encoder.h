// Video output through FFmpeg: the one place gdvr talks to libavcodec,
// libavformat and libswscale. Frames arrive display-encoded (after the OCIO
// view transform, see color_transform.h), in order, one at a time as the
// renderer finalises them; close() flushes the encoder and atomically moves
// the finished file into place.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/image/image.h"
#include "core/util/status.h"

namespace gdvr {

enum class VideoCodec {
  kH264,    // libx264 (or another H.264 encoder), yuv420p 8-bit, .mp4: delivery
  kProRes,  // prores_ks HQ, yuv422p10le, .mov: editing
  kFfv1,    // FFV1 level 3, gbrp10le (lossless RGB), .mkv: archival
};

const char* video_codec_name(VideoCodec codec);  // "h264", "prores", "ffv1"
Expected<VideoCodec> parse_video_codec(const std::string& name);
// Container used when the output path has no recognised extension.
const char* default_video_extension(VideoCodec codec);  // "mp4", "mov", "mkv"

struct VideoEncoderOptions {
  VideoCodec codec = VideoCodec::kH264;
  int width = 0;  // of the frames passed to add_frame(); required
  int height = 0;
  int fps_num = 24;  // frame rate as a rational: 30000/1001 for NTSC
  int fps_den = 1;
  int h264_crf = 18;  // x264 constant quality; 18 is visually lossless
  // 4:2:0 (H.264) needs even width and height, 4:2:2 (ProRes) an even width.
  // true: replicate the last column/row to the next even size; false: reject.
  bool pad_to_even = true;
};

class VideoEncoder {
 public:
  // Opens `path` (really "<path>.tmp.<pid>" until close()) and writes the
  // container header. The muxer follows the extension (.mp4/.mov/.mkv) when it
  // has one FFmpeg knows, else the codec's default container.
  static Expected<std::unique_ptr<VideoEncoder>> open(const std::string& path,
                                                      const VideoEncoderOptions& options);

  VideoEncoder(const VideoEncoder&) = delete;
  VideoEncoder& operator=(const VideoEncoder&) = delete;
  // Without a successful close() the partial file is deleted: an aborted
  // render leaves no truncated video behind.
  ~VideoEncoder();

  // Appends one frame of display-encoded RGB in [0, 1] (>= 3 channels, the
  // size given at open(); values outside [0, 1] clip).
  Status add_frame(const Image& display_rgb);

  // Drains the encoder, writes the trailer and renames into place. Further
  // calls to add_frame() fail.
  Status close();

  int64_t frames_written() const;
  // Size actually encoded (the frame size padded to even where needed).
  int encoded_width() const;
  int encoded_height() const;
  const std::string& path() const;

 private:
  struct Impl;
  explicit VideoEncoder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace gdvr
