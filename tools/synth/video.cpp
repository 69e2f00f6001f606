#include "video.hpp"

#include "failure.hpp"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
}

#include <cstring>

namespace synth {

namespace {

std::string av_text(int err)
{
	char text[AV_ERROR_MAX_STRING_SIZE] = "";
	av_strerror(err, text, sizeof text);
	return text;
}

} // namespace

void VideoWriter::fail(const std::string &what, int err)
{
	release();
	throw Failure(kExitFailure, what + ": " + av_text(err));
}

VideoWriter::~VideoWriter()
{
	release();
}

void VideoWriter::release()
{
	av_packet_free(&pkt_);
	av_frame_free(&frame_);
	avcodec_free_context(&enc_);
	if (fmt_) {
		avio_closep(&fmt_->pb);
		avformat_free_context(fmt_);
		fmt_ = nullptr;
	}
	st_ = nullptr;
	header_ = false;
}

void VideoWriter::open(const std::string &path, bool raw, double fps, int width, int height)
{
	path_ = path;
	const std::string what = std::string("the ") + (raw ? "rawvideo" : "FFV1") + " codec";
	auto fail = [&](const std::string &why, int err) {
		release();
		throw Failure(kExitFailure, "cannot write " + path_ + " (FFmpeg, " + what + "): " +
						    why + (err < 0 ? ": " + av_text(err) : ""));
	};
	int err = avformat_alloc_output_context2(&fmt_, nullptr, "matroska", path.c_str());
	if (err < 0)
		fail("no Matroska muxer", err);
	const AVCodec *codec = avcodec_find_encoder(raw ? AV_CODEC_ID_RAWVIDEO : AV_CODEC_ID_FFV1);
	if (!codec)
		fail("no encoder", 0);
	st_ = avformat_new_stream(fmt_, nullptr);
	enc_ = avcodec_alloc_context3(codec);
	frame_ = av_frame_alloc();
	pkt_ = av_packet_alloc();
	if (!st_ || !enc_ || !frame_ || !pkt_)
		fail("out of memory", 0);
	enc_->width = width;
	enc_->height = height;
	enc_->pix_fmt = AV_PIX_FMT_GRAY8; // both codecs store grey as it is, at any width
	// Frame i at i / fps: the time base OpenCV's writer used (1/10 s at 10 fps).
	enc_->time_base = av_inv_q(av_d2q(fps, 1000000));
	enc_->framerate = av_d2q(fps, 1000000);
	// A key frame every 12, as OpenCV's writer had it: FFV1 restarts its context models
	// there, which keeps the files (and their decoding cost) as they were.
	enc_->gop_size = 12;
	enc_->thread_count = 1; // the same bytes on any machine
	if (fmt_->oformat->flags & AVFMT_GLOBALHEADER)
		enc_->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
	err = avcodec_open2(enc_, codec, nullptr);
	if (err < 0)
		fail("cannot open the encoder", err);
	err = avcodec_parameters_from_context(st_->codecpar, enc_);
	if (err < 0)
		fail("stream parameters", err);
	// Matroska's uncompressed video names its pixel layout by FourCC: Y800, 8-bit grey, as
	// OpenCV's writer wrote it.
	if (raw)
		st_->codecpar->codec_tag = MKTAG('Y', '8', '0', '0');
	st_->time_base = enc_->time_base;
	st_->avg_frame_rate = enc_->framerate;
	frame_->format = AV_PIX_FMT_GRAY8;
	frame_->width = width;
	frame_->height = height;
	err = av_frame_get_buffer(frame_, 0);
	if (err < 0)
		fail("frame buffer", err);
	// Matroska's segment and track UIDs are random unless bit-exact (44 bytes of a 64x48
	// file differed between two runs): the same arguments and seed now give the same bytes,
	// as the README says of mvod-synth's output.
	fmt_->flags |= AVFMT_FLAG_BITEXACT;
	err = avio_open(&fmt_->pb, path.c_str(), AVIO_FLAG_WRITE);
	if (err < 0)
		fail("cannot create the file", err);
	err = avformat_write_header(fmt_, nullptr);
	if (err < 0)
		fail("cannot write the header", err);
	header_ = true;
	frames_ = 0;
}

void VideoWriter::drain()
{
	for (;;) {
		int err = avcodec_receive_packet(enc_, pkt_);
		if (err == AVERROR(EAGAIN) || err == AVERROR_EOF)
			return;
		if (err >= 0) {
			av_packet_rescale_ts(pkt_, enc_->time_base, st_->time_base);
			pkt_->stream_index = st_->index;
			err = av_interleaved_write_frame(fmt_, pkt_); // takes the packet's data
		}
		if (err < 0)
			fail("cannot write " + path_, err);
	}
}

void VideoWriter::write(const cv::Mat &grey)
{
	CV_Assert(enc_ && grey.type() == CV_8UC1 && grey.cols == enc_->width &&
		  grey.rows == enc_->height);
	// The encoder may still hold the last frame's buffer (rawvideo wraps it in the packet):
	// a buffer of our own again before writing into it.
	int err = av_frame_make_writable(frame_);
	if (err < 0)
		fail("cannot write " + path_, err);
	for (int y = 0; y < grey.rows; y++)
		std::memcpy(frame_->data[0] + (ptrdiff_t)y * frame_->linesize[0], grey.ptr(y),
			    size_t(grey.cols));
	frame_->pts = frames_++;
	err = avcodec_send_frame(enc_, frame_);
	if (err < 0)
		fail("cannot encode a frame for " + path_, err);
	drain();
}

void VideoWriter::close()
{
	if (!header_) {
		release();
		return;
	}
	int err = avcodec_send_frame(enc_, nullptr);
	if (err >= 0)
		drain();
	if (err >= 0)
		err = av_write_trailer(fmt_);
	if (err >= 0)
		err = avio_closep(&fmt_->pb);
	if (err < 0)
		fail("cannot finish " + path_, err);
	release();
}

} // namespace synth
