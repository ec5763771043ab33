#include "core/io/video_encoder.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <cmath>
#include <mutex>
#include <vector>

#include "core/io/atomic_file.h"

namespace gdvr {
namespace {

// ---- RAII for FFmpeg objects -----------------------------------------------

struct CodecContextDeleter {
  void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct FrameDeleter {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct PacketDeleter {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct SwsDeleter {
  void operator()(SwsContext* s) const { sws_freeContext(s); }
};
struct DictDeleter {
  void operator()(AVDictionary* d) const { av_dict_free(&d); }
};
// Output format context plus its AVIOContext (which avformat_free_context
// does not close).
struct OutputDeleter {
  void operator()(AVFormatContext* f) const {
    if (f->pb && !(f->oformat->flags & AVFMT_NOFILE)) avio_closep(&f->pb);
    avformat_free_context(f);
  }
};
using CodecContextPtr = std::unique_ptr<AVCodecContext, CodecContextDeleter>;
using FramePtr = std::unique_ptr<AVFrame, FrameDeleter>;
using PacketPtr = std::unique_ptr<AVPacket, PacketDeleter>;
using SwsPtr = std::unique_ptr<SwsContext, SwsDeleter>;
using OutputPtr = std::unique_ptr<AVFormatContext, OutputDeleter>;

std::string av_error(int err) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(err, buf, sizeof(buf));
  return buf;
}

constexpr int kMaxVideoDimension = 16384;

struct CodecSetup {
  AVPixelFormat pix_fmt;
  bool even_width, even_height;
  AVColorTransferCharacteristic trc;
  AVColorSpace matrix;
  AVColorRange range;
};

// Delivery codecs are tagged BT.709 throughout, limited range: what players
// and editors assume for HD video. FFV1 stores the display-encoded RGB
// losslessly, so it is tagged with what the pixels really are: sRGB-encoded
// Rec.709 primaries, full range RGB.
CodecSetup setup_for(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264:
      return {AV_PIX_FMT_YUV420P, true, true, AVCOL_TRC_BT709, AVCOL_SPC_BT709, AVCOL_RANGE_MPEG};
    case VideoCodec::kProRes:
      return {AV_PIX_FMT_YUV422P10LE, true, false, AVCOL_TRC_BT709, AVCOL_SPC_BT709,
              AVCOL_RANGE_MPEG};
    case VideoCodec::kFfv1:
      break;
  }
  return {AV_PIX_FMT_GBRP10LE, false, false, AVCOL_TRC_IEC61966_2_1, AVCOL_SPC_RGB,
          AVCOL_RANGE_JPEG};
}

const AVCodec* find_encoder(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264:
      // libx264 by name first: avcodec_find_encoder(H264) may pick a hardware
      // encoder that needs a device we do not set up.
      if (const AVCodec* c = avcodec_find_encoder_by_name("libx264")) return c;
      return avcodec_find_encoder(AV_CODEC_ID_H264);
    case VideoCodec::kProRes:
      if (const AVCodec* c = avcodec_find_encoder_by_name("prores_ks")) return c;
      return avcodec_find_encoder(AV_CODEC_ID_PRORES);
    case VideoCodec::kFfv1:
      return avcodec_find_encoder(AV_CODEC_ID_FFV1);
  }
  return nullptr;
}

bool supports_pix_fmt(const AVCodec* codec, AVPixelFormat fmt) {
  if (!codec->pix_fmts) return true;  // encoder does not declare: let open decide
  for (const AVPixelFormat* p = codec->pix_fmts; *p != AV_PIX_FMT_NONE; ++p)
    if (*p == fmt) return true;
  return false;
}

std::string extension_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return path.substr(dot + 1);
}

}  // namespace

const char* video_codec_name(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264: return "h264";
    case VideoCodec::kProRes: return "prores";
    case VideoCodec::kFfv1: return "ffv1";
  }
  return "?";
}

Expected<VideoCodec> parse_video_codec(const std::string& name) {
  if (name == "h264") return VideoCodec::kH264;
  if (name == "prores") return VideoCodec::kProRes;
  if (name == "ffv1") return VideoCodec::kFfv1;
  return invalid_argument("unknown video codec '" + name + "' (expected h264, prores or ffv1)");
}

const char* default_video_extension(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264: return "mp4";
    case VideoCodec::kProRes: return "mov";
    case VideoCodec::kFfv1: return "mkv";
  }
  return "mkv";
}

struct VideoEncoder::Impl {
  std::string path, tmp_path;
  VideoEncoderOptions options;
  std::string label;  // "h264 (libx264) 'out.mp4'" for error messages
  int enc_width = 0, enc_height = 0;
  OutputPtr fmt;
  CodecContextPtr ctx;
  AVStream* stream = nullptr;  // owned by fmt
  FramePtr frame;
  PacketPtr packet;
  SwsPtr sws;
  std::vector<uint16_t> rgb48;  // padded staging frame, RGB48 host-endian
  int64_t next_pts = 0;
  bool closed = false;
  bool failed = false;

  Status fail(const std::string& what) {
    failed = true;
    return internal_error(label + ": " + what);
  }

  // Sends `f` (nullptr: flush) and writes every packet the encoder has ready.
  Status encode(const AVFrame* f) {
    int err = avcodec_send_frame(ctx.get(), f);
    if (err < 0) return fail("sending frame to encoder: " + av_error(err));
    for (;;) {
      err = avcodec_receive_packet(ctx.get(), packet.get());
      if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) return Status::Ok();
      if (err < 0) return fail("encoding: " + av_error(err));
      av_packet_rescale_ts(packet.get(), ctx->time_base, stream->time_base);
      packet->stream_index = stream->index;
      err = av_interleaved_write_frame(fmt.get(), packet.get());  // takes the packet's reference
      if (err < 0) return fail("writing packet: " + av_error(err));
    }
  }

  void abandon() {
    // Drop the muxer (closing the file) before deleting it.
    fmt.reset();
    discard_temporary(tmp_path);
  }
};

VideoEncoder::VideoEncoder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

VideoEncoder::~VideoEncoder() {
  if (impl_ && !impl_->closed) impl_->abandon();
}

int64_t VideoEncoder::frames_written() const { return impl_->next_pts; }
int VideoEncoder::encoded_width() const { return impl_->enc_width; }
int VideoEncoder::encoded_height() const { return impl_->enc_height; }
const std::string& VideoEncoder::path() const { return impl_->path; }

Expected<std::unique_ptr<VideoEncoder>> VideoEncoder::open(const std::string& path,
                                                           const VideoEncoderOptions& options) {
  // libx264 and the muxers print statistics to stderr on every file; a render
  // server writing many videos should only see real errors, which reach the
  // caller as Status anyway. FFmpeg is wrapped only here, so the global log
  // level is ours to set.
  static std::once_flag quiet_once;
  std::call_once(quiet_once, [] { av_log_set_level(AV_LOG_ERROR); });

  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->tmp_path = temporary_path_for(path);
  impl->options = options;
  const char* codec_name = video_codec_name(options.codec);
  impl->label = std::string(codec_name) + " video '" + path + "'";

  // ---- Validate options ----
  if (options.width <= 0 || options.height <= 0 || options.width > kMaxVideoDimension ||
      options.height > kMaxVideoDimension)
    return invalid_argument(impl->label + ": invalid frame size " + std::to_string(options.width) +
                            "x" + std::to_string(options.height));
  if (options.fps_num <= 0 || options.fps_den <= 0)
    return invalid_argument(impl->label + ": invalid frame rate " + std::to_string(options.fps_num) +
                            "/" + std::to_string(options.fps_den));
  const CodecSetup setup = setup_for(options.codec);
  impl->enc_width = options.width + (setup.even_width ? options.width % 2 : 0);
  impl->enc_height = options.height + (setup.even_height ? options.height % 2 : 0);
  if (!options.pad_to_even && (impl->enc_width != options.width || impl->enc_height != options.height))
    return invalid_argument(impl->label + ": " + av_get_pix_fmt_name(setup.pix_fmt) + " needs even " +
                            (setup.even_height ? "width and height" : "width") + ", got " +
                            std::to_string(options.width) + "x" + std::to_string(options.height) +
                            " (enable pad_to_even)");

  const AVCodec* codec = find_encoder(options.codec);
  if (!codec)
    return unimplemented(impl->label + ": no " + codec_name + " encoder in this FFmpeg build");
  impl->label = std::string(codec_name) + " (" + codec->name + ") video '" + path + "'";
  if (!supports_pix_fmt(codec, setup.pix_fmt))
    return unimplemented(impl->label + ": encoder does not support " +
                         av_get_pix_fmt_name(setup.pix_fmt));

  // ---- Muxer ----
  const std::string ext = extension_of(path);
  const AVOutputFormat* ofmt = ext.empty() ? nullptr : av_guess_format(nullptr, path.c_str(), nullptr);
  if (!ofmt) {
    const std::string fallback = std::string("out.") + default_video_extension(options.codec);
    ofmt = av_guess_format(nullptr, fallback.c_str(), nullptr);
  }
  if (!ofmt) return unimplemented(impl->label + ": no muxer available");
  if (avformat_query_codec(ofmt, codec->id, FF_COMPLIANCE_NORMAL) != 1)
    return invalid_argument(impl->label + ": container '" + ofmt->name + "' cannot hold " +
                            codec_name + "; use ." + default_video_extension(options.codec));
  AVFormatContext* raw_fmt = nullptr;
  // Format passed explicitly: the temporary name's ".tmp.<pid>" suffix would
  // defeat guessing by extension.
  int err = avformat_alloc_output_context2(&raw_fmt, ofmt, nullptr, impl->tmp_path.c_str());
  if (err < 0 || !raw_fmt) return internal_error(impl->label + ": allocating muxer: " + av_error(err));
  impl->fmt.reset(raw_fmt);

  // ---- Encoder ----
  impl->ctx.reset(avcodec_alloc_context3(codec));
  if (!impl->ctx) return internal_error(impl->label + ": cannot allocate encoder context");
  AVCodecContext* c = impl->ctx.get();
  c->width = impl->enc_width;
  c->height = impl->enc_height;
  c->pix_fmt = setup.pix_fmt;
  c->time_base = AVRational{options.fps_den, options.fps_num};
  c->framerate = AVRational{options.fps_num, options.fps_den};
  c->sample_aspect_ratio = AVRational{1, 1};
  // Rendered frames are progressive; said so, QuickTime files carry a 'fiel'
  // atom (ProRes), which editors otherwise may guess wrong (field order unknown).
  c->field_order = AV_FIELD_PROGRESSIVE;
  c->color_primaries = AVCOL_PRI_BT709;
  c->color_trc = setup.trc;
  c->colorspace = setup.matrix;
  c->color_range = setup.range;
  if (options.codec == VideoCodec::kH264) c->chroma_sample_location = AVCHROMA_LOC_LEFT;
  // A keyframe every ~2 s: seekable previews without hurting compression.
  c->gop_size = std::max(1, int(std::lround(2.0 * options.fps_num / options.fps_den)));
  if (ofmt->flags & AVFMT_GLOBALHEADER) c->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;

  AVDictionary* raw_opts = nullptr;
  switch (options.codec) {
    case VideoCodec::kH264:
      if (std::string(codec->name) == "libx264") {
        av_dict_set(&raw_opts, "crf", std::to_string(options.h264_crf).c_str(), 0);
        av_dict_set(&raw_opts, "preset", "medium", 0);
      }
      break;
    case VideoCodec::kProRes:
      av_dict_set(&raw_opts, "profile", "hq", 0);
      // Apple's vendor id makes Final Cut and QuickTime accept the stream.
      av_dict_set(&raw_opts, "vendor", "apl0", 0);
      break;
    case VideoCodec::kFfv1:
      c->level = 3;  // slices + CRCs: self-checking archive, multithreaded decode
      av_dict_set(&raw_opts, "slicecrc", "1", 0);
      break;
  }
  std::unique_ptr<AVDictionary, DictDeleter> codec_opts(raw_opts);
  raw_opts = codec_opts.release();
  err = avcodec_open2(c, codec, &raw_opts);
  codec_opts.reset(raw_opts);  // leftovers: options the encoder did not take
  if (err < 0) return internal_error(impl->label + ": opening encoder: " + av_error(err));

  impl->stream = avformat_new_stream(impl->fmt.get(), nullptr);
  if (!impl->stream) return internal_error(impl->label + ": cannot add stream");
  impl->stream->time_base = c->time_base;
  impl->stream->avg_frame_rate = c->framerate;
  impl->stream->r_frame_rate = c->framerate;
  err = avcodec_parameters_from_context(impl->stream->codecpar, c);
  if (err < 0) return internal_error(impl->label + ": stream parameters: " + av_error(err));

  // ---- Frames and colour conversion ----
  impl->frame.reset(av_frame_alloc());
  impl->packet.reset(av_packet_alloc());
  if (!impl->frame || !impl->packet) return internal_error(impl->label + ": out of memory");
  impl->frame->format = c->pix_fmt;
  impl->frame->width = c->width;
  impl->frame->height = c->height;
  impl->frame->color_primaries = c->color_primaries;
  impl->frame->color_trc = c->color_trc;
  impl->frame->colorspace = c->colorspace;
  impl->frame->color_range = c->color_range;
  err = av_frame_get_buffer(impl->frame.get(), 0);
  if (err < 0) return internal_error(impl->label + ": frame buffer: " + av_error(err));

  // 16-bit RGB staging keeps 10-bit targets free of 8-bit banding. Full
  // chroma input plus accurate rounding: the default fast path averages
  // chroma crudely and shifts colours on thin edges.
  impl->sws.reset(sws_getContext(c->width, c->height, AV_PIX_FMT_RGB48, c->width, c->height,
                                 c->pix_fmt, SWS_BICUBIC | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INP,
                                 nullptr, nullptr, nullptr));
  if (!impl->sws) return internal_error(impl->label + ": no swscale path RGB48 -> " +
                                        av_get_pix_fmt_name(c->pix_fmt));
  // RGB -> YUV with BT.709 coefficients into limited range (swscale's
  // default would be BT.601); ignored for the RGB (FFV1) target.
  const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
  sws_setColorspaceDetails(impl->sws.get(), bt709, /* srcRange = */ 1, bt709,
                           /* dstRange = */ setup.range == AVCOL_RANGE_JPEG ? 1 : 0,
                           /* brightness = */ 0, /* contrast = */ 1 << 16, /* saturation = */ 1 << 16);
  impl->rgb48.resize(size_t(c->width) * c->height * 3);

  // ---- Container header ----
  if (!(ofmt->flags & AVFMT_NOFILE)) {
    err = avio_open(&impl->fmt->pb, impl->tmp_path.c_str(), AVIO_FLAG_WRITE);
    if (err < 0)
      return internal_error(impl->label + ": cannot create '" + impl->tmp_path +
                            "': " + av_error(err));
  }
  AVDictionary* mux_raw = nullptr;
  // Index at the front so players can start before the whole file arrives.
  if (std::string(ofmt->name).find("mp4") != std::string::npos || std::string(ofmt->name) == "mov")
    av_dict_set(&mux_raw, "movflags", "+faststart", 0);
  std::unique_ptr<AVDictionary, DictDeleter> mux_opts(mux_raw);
  mux_raw = mux_opts.release();
  err = avformat_write_header(impl->fmt.get(), &mux_raw);
  mux_opts.reset(mux_raw);
  if (err < 0) {
    impl->abandon();
    return internal_error(impl->label + ": writing header: " + av_error(err));
  }
  return std::unique_ptr<VideoEncoder>(new VideoEncoder(std::move(impl)));
}

Status VideoEncoder::add_frame(const Image& display_rgb) {
  Impl& m = *impl_;
  if (m.closed) return failed_precondition(m.label + ": add_frame after close");
  if (m.failed) return failed_precondition(m.label + ": encoder failed earlier");
  if (display_rgb.width() != m.options.width || display_rgb.height() != m.options.height ||
      display_rgb.channels() < 3)
    return invalid_argument(m.label + ": frame " + std::to_string(m.next_pts) + " is " +
                            std::to_string(display_rgb.width()) + "x" +
                            std::to_string(display_rgb.height()) + "x" +
                            std::to_string(display_rgb.channels()) + ", expected " +
                            std::to_string(m.options.width) + "x" + std::to_string(m.options.height) +
                            " with >= 3 channels");

  // ---- Quantise to RGB48, replicating the edge into the padding ----
  const int nc = display_rgb.channels();
  for (int y = 0; y < m.enc_height; ++y) {
    const int sy = std::min(y, m.options.height - 1);
    uint16_t* row = m.rgb48.data() + size_t(y) * m.enc_width * 3;
    for (int x = 0; x < m.enc_width; ++x) {
      const int sx = std::min(x, m.options.width - 1);
      const float* p = display_rgb.data().data() + (size_t(sy) * m.options.width + sx) * nc;
      for (int c = 0; c < 3; ++c) {
        const float v = !(p[c] > 0.0f) ? 0.0f : std::min(p[c], 1.0f);  // NaN -> 0
        row[x * 3 + c] = uint16_t(std::lround(v * 65535.0f));
      }
    }
  }

  // The encoder may still hold a reference to the previous frame's buffers.
  int err = av_frame_make_writable(m.frame.get());
  if (err < 0) return m.fail("frame not writable: " + av_error(err));
  const uint8_t* src[1] = {reinterpret_cast<const uint8_t*>(m.rgb48.data())};
  const int src_stride[1] = {m.enc_width * 3 * int(sizeof(uint16_t))};
  sws_scale(m.sws.get(), src, src_stride, 0, m.enc_height, m.frame->data, m.frame->linesize);
  m.frame->pts = m.next_pts;
  GDVR_RETURN_IF_ERROR(m.encode(m.frame.get()));
  ++m.next_pts;
  return Status::Ok();
}

Status VideoEncoder::close() {
  Impl& m = *impl_;
  if (m.closed) return failed_precondition(m.label + ": already closed");
  if (m.failed) {
    m.closed = true;
    m.abandon();
    return failed_precondition(m.label + ": encoder failed earlier; partial file removed");
  }
  m.closed = true;
  if (m.next_pts == 0) {
    m.abandon();
    return failed_precondition(m.label + ": no frames were added; nothing written");
  }
  Status st = m.encode(nullptr);
  if (st.ok()) {
    const int err = av_write_trailer(m.fmt.get());
    if (err < 0) st = internal_error(m.label + ": writing trailer: " + av_error(err));
  }
  if (st.ok() && m.fmt->pb) {
    const int err = avio_closep(&m.fmt->pb);
    if (err < 0) st = internal_error(m.label + ": closing file: " + av_error(err));
  }
  if (!st.ok()) {
    m.abandon();
    return st;
  }
  m.fmt.reset();
  return commit_temporary(m.tmp_path, m.path);
}

}  // namespace gdvr
