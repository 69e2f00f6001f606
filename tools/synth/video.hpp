// video.mkv: 8-bit grey frames into Matroska, lossless (FFV1, or rawvideo for --codec raw),
// through FFmpeg's libraries directly. OpenCV's VideoWriter (4.6) rounds both sides down to
// even ("some internal functions inside FFMPEG swscale require even width/height") and drops
// the last column or row, so a 1241x376 rendering became a 1240x376 video beside a calibration
// for 1241x376. Grey needs no conversion, and FFV1 and rawvideo take any width and height, so
// this writer stores exactly the size it is given.
#pragma once

#include <opencv2/core.hpp>

#include <string>

struct AVCodecContext;
struct AVFormatContext;
struct AVFrame;
struct AVPacket;
struct AVStream;

namespace synth {

class VideoWriter {
public:
	VideoWriter() = default;
	VideoWriter(const VideoWriter &) = delete;
	VideoWriter &operator=(const VideoWriter &) = delete;
	~VideoWriter();

	// Creates path (any earlier file replaced) for width x height frames at fps frames a
	// second; throws Failure if FFmpeg cannot.
	void open(const std::string &path, bool raw, double fps, int width, int height);
	// One CV_8UC1 frame of the size given to open; frame i is stamped i / fps seconds.
	void write(const cv::Mat &grey);
	// Flushes the encoder and finishes the file; throws Failure on a write error. Safe to call
	// when nothing is open.
	void close();

private:
	void drain();
	void release();
	// Releases everything and throws Failure "what: FFmpeg's text for err".
	[[noreturn]] void fail(const std::string &what, int err);

	std::string path_;
	AVFormatContext *fmt_ = nullptr;
	AVCodecContext *enc_ = nullptr;
	AVStream *st_ = nullptr;
	AVFrame *frame_ = nullptr;
	AVPacket *pkt_ = nullptr;
	long long frames_ = 0;
	bool header_ = false; // the header is written: the trailer must be too
};

} // namespace synth
