/*
 * mkvideo: writes the videos the source tests need and that OpenCV's VideoWriter cannot make:
 * frames at chosen times (variable frame rate) and of chosen sizes (a resolution change
 * mid-stream). Test-only; FFmpeg's own libraries, which OpenCV's video I/O already pulls in.
 *
 *   mkvideo OUT CODEC[:PIXFMT] WxH@MS...   e.g. mkvideo vfr.mkv ffv1 64x48@0 64x48@33 64x48@400
 *
 * A bare WxH sets the size without a frame: mkvideo empty.mkv ffv1 64x48 is a video of none.
 *
 * Every frame is a key frame (a size change may come at any frame), YUV 4:2:0 unless PIXFMT
 * says gray or bgr0, a pattern that moves with the frame number: mkvideo_level(x, y, i) in the
 * luma (grey) plane, or in R with G and B derived from it (bgr0: mkvideo_bgr). The container
 * follows OUT's extension; a size change needs a codec whose stream carries its size in-band
 * (mpeg2video in .ts).
 */
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/pixdesc.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct out {
	AVFormatContext *fmt;
	AVStream *st;
	const AVCodec *codec;
	AVCodecContext *enc;
	AVRational tb;
	enum AVPixelFormat pix;
};

/* The pattern; tests/integration/test_video.c computes the same. */
static uint8_t mkvideo_level(int x, int y, int i)
{
	return (uint8_t)((x * 7 + y * 3 + i * 5) ^ (x * y));
}

/* bgr0's pixel: R the pattern, G and B other functions of it, so every channel differs. */
static void mkvideo_bgr(int x, int y, int i, uint8_t *p)
{
	uint8_t r = mkvideo_level(x, y, i);
	p[0] = (uint8_t)(255 - r);
	p[1] = (uint8_t)(r ^ 0x5a);
	p[2] = r;
	p[3] = 0;
}

static void check(int ret, const char *what)
{
	if (ret >= 0)
		return;
	fprintf(stderr, "mkvideo: %s: %s\n", what, av_err2str(ret));
	exit(1);
}

static void drain(struct out *o)
{
	AVPacket *pkt = av_packet_alloc();
	while (avcodec_receive_packet(o->enc, pkt) == 0) {
		av_packet_rescale_ts(pkt, o->enc->time_base, o->st->time_base);
		pkt->stream_index = 0;
		check(av_interleaved_write_frame(o->fmt, pkt), "writing a packet");
	}
	av_packet_free(&pkt);
}

static void close_encoder(struct out *o)
{
	if (!o->enc)
		return;
	check(avcodec_send_frame(o->enc, NULL), "flushing the encoder");
	drain(o);
	avcodec_free_context(&o->enc);
}

static void open_encoder(struct out *o, int w, int h)
{
	close_encoder(o);
	o->enc = avcodec_alloc_context3(o->codec);
	o->enc->width = w;
	o->enc->height = h;
	o->enc->pix_fmt = o->pix;
	o->enc->time_base = o->tb;
	o->enc->framerate = av_inv_q(o->tb);
	o->enc->gop_size = 1;
	o->enc->max_b_frames = 0;
	if (o->fmt->oformat->flags & AVFMT_GLOBALHEADER)
		o->enc->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
	check(avcodec_open2(o->enc, o->codec, NULL), "opening the encoder");
}

static void put_frame(struct out *o, int w, int h, long ms, int i)
{
	AVFrame *f = av_frame_alloc();
	f->width = w;
	f->height = h;
	f->format = o->pix;
	check(av_frame_get_buffer(f, 0), "allocating a frame");
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			uint8_t *row = f->data[0] + y * f->linesize[0];
			if (o->pix == AV_PIX_FMT_BGR0)
				mkvideo_bgr(x, y, i, row + 4 * x);
			else
				row[x] = mkvideo_level(x, y, i);
		}
	if (o->pix == AV_PIX_FMT_YUV420P)
		for (int p = 1; p < 3; p++)
			memset(f->data[p], 128, (size_t)f->linesize[p] * (size_t)((h + 1) / 2));
	f->pts = av_rescale_q(ms, (AVRational){1, 1000}, o->tb);
	check(avcodec_send_frame(o->enc, f), "encoding a frame");
	drain(o);
	av_frame_free(&f);
}

int main(int argc, char **argv)
{
	if (argc < 4) {
		fprintf(stderr, "usage: mkvideo OUT CODEC[:PIXFMT] WxH@MS...\n");
		return 2;
	}
	char codec[64];
	snprintf(codec, sizeof(codec), "%s", argv[2]);
	char *pix = strchr(codec, ':');
	if (pix)
		*pix++ = '\0';
	struct out o = {.codec = avcodec_find_encoder_by_name(codec),
			.pix = pix ? av_get_pix_fmt(pix) : AV_PIX_FMT_YUV420P};
	if (o.pix != AV_PIX_FMT_YUV420P && o.pix != AV_PIX_FMT_GRAY8 && o.pix != AV_PIX_FMT_BGR0) {
		fprintf(stderr, "mkvideo: pixel format %s is none of yuv420p, gray, bgr0\n", pix);
		return 2;
	}
	if (!o.codec) {
		fprintf(stderr, "mkvideo: no encoder %s\n", argv[2]);
		return 1;
	}
	/* MPEG-2 only knows the standard rates; the others take millisecond times. */
	o.tb = strcmp(codec, "mpeg2video") == 0 ? (AVRational){1, 25} : (AVRational){1, 1000};
	check(avformat_alloc_output_context2(&o.fmt, NULL, NULL, argv[1]), "choosing a container");
	o.st = avformat_new_stream(o.fmt, NULL);
	int w0 = 0, h0 = 0;
	for (int i = 3; i < argc; i++) {
		int w, h, n = 0;
		long ms;
		bool frame = sscanf(argv[i], "%dx%d@%ld", &w, &h, &ms) == 3;
		if (!frame && (sscanf(argv[i], "%dx%d%n", &w, &h, &n) != 2 || argv[i][n])) {
			fprintf(stderr, "mkvideo: %s is not WxH@MS\n", argv[i]);
			return 2;
		}
		if (w != w0 || h != h0) {
			open_encoder(&o, w, h);
			if (i == 3) {
				o.st->time_base = o.tb;
				check(avcodec_parameters_from_context(o.st->codecpar, o.enc), "stream");
				check(avio_open(&o.fmt->pb, argv[1], AVIO_FLAG_WRITE), argv[1]);
				check(avformat_write_header(o.fmt, NULL), "writing the header");
			}
			w0 = w;
			h0 = h;
		}
		if (frame)
			put_frame(&o, w, h, ms, i - 3);
	}
	close_encoder(&o);
	check(av_write_trailer(o.fmt), "writing the trailer");
	avio_closep(&o.fmt->pb);
	avformat_free_context(o.fmt);
	return 0;
}
