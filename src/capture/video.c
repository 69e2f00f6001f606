#include "capture/video.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>

#include "capture/image_header.h"

struct mvod_video {
	AVFormatContext *fmt;
	AVCodecContext *dec;
	AVPacket *pkt;      /* reused for every packet */
	AVFrame *frame;     /* the frame last handed out; the decoder's buffer, referenced */
	struct SwsContext *sws; /* frames whose first plane is no 8-bit luma -> grey */
	uint8_t *grey;      /* w x h: converted or range-expanded frames; allocated at open */
	int stream;
	int w, h;           /* the size the container declares: every frame handed out has it */
	int64_t start;      /* the stream's first time, in its time base (0 when unknown) */
	AVRational tb;
	bool draining;      /* the demuxer is done; the decoder is being flushed */
	bool primed;        /* frame holds the first frame, decoded at open, not yet read */
	uint8_t range[256]; /* limited-range (16-235) luma -> full range, as swscale's BGR had it */
};

void mvod_video_close(struct mvod_video *v)
{
	if (!v)
		return;
	sws_freeContext(v->sws);
	av_free(v->grey);
	av_frame_free(&v->frame);
	av_packet_free(&v->pkt);
	avcodec_free_context(&v->dec);
	avformat_close_input(&v->fmt);
	free(v);
}

/*
 * One decoding thread: on one core more would only switch, and on two the capture thread that
 * decodes already runs beside the VO's (capture.c); frame threads would also hold frames back.
 */
static int open_decoder(struct mvod_video *v)
{
	const AVCodecParameters *par = v->fmt->streams[v->stream]->codecpar;
	const AVCodec *codec = avcodec_find_decoder(par->codec_id);
	if (!codec)
		return -EINVAL;
	v->dec = avcodec_alloc_context3(codec);
	if (!v->dec)
		return -ENOMEM;
	if (avcodec_parameters_to_context(v->dec, par) < 0)
		return -EINVAL;
	v->dec->thread_count = 1;
	/*
	 * A frame whose header states far more pixels than the stream's is refused, not
	 * allocated. FFmpeg checks its buffers' padded size against this: (w + 64)(h + 64)
	 * refused every frame of a 64x48 MPEG-2 stream, four times that passes them; a bomb's
	 * 30000x30000 in a 640x480 stream is 600 times.
	 */
	if (v->w > 0 && v->h > 0)
		v->dec->max_pixels = 4 * (int64_t)(v->w + 64) * (v->h + 64);
	if (avcodec_open2(v->dec, codec, NULL) < 0)
		return -EINVAL;
	v->pkt = av_packet_alloc();
	v->frame = av_frame_alloc();
	return v->pkt && v->frame ? 0 : -ENOMEM;
}

static int open_stream(struct mvod_video *v, const char *path)
{
	if (avformat_open_input(&v->fmt, path, NULL, NULL) < 0)
		return -EINVAL;
	if (avformat_find_stream_info(v->fmt, NULL) < 0)
		return -EINVAL;
	v->stream = av_find_best_stream(v->fmt, AVMEDIA_TYPE_VIDEO, -1, -1, NULL, 0);
	if (v->stream < 0)
		return -EINVAL;
	/* Only the video stream is demuxed into packets; audio and subtitles are skipped. */
	for (unsigned i = 0; i < v->fmt->nb_streams; i++)
		v->fmt->streams[i]->discard = (int)i == v->stream ? AVDISCARD_DEFAULT : AVDISCARD_ALL;
	const AVStream *st = v->fmt->streams[v->stream];
	v->w = st->codecpar->width;
	v->h = st->codecpar->height;
	v->tb = st->time_base;
	v->start = st->start_time == AV_NOPTS_VALUE ? 0 : st->start_time;
	if ((int64_t)v->w * v->h > MVOD_FRAME_MAX_PIXELS)
		return -E2BIG;
	if (v->w <= 0 || v->h <= 0 || v->w > 65535 || v->h > 65535)
		return 0; /* props says so; mvod_video_read refuses every frame */
	v->grey = av_malloc((size_t)v->w * (size_t)v->h);
	return v->grey ? 0 : -ENOMEM;
}

/* The next decoded frame into v->frame: 0, or -ENODATA once the decoder is flushed. */
static int decode(struct mvod_video *v)
{
	for (;;) {
		int ret = avcodec_receive_frame(v->dec, v->frame);
		if (ret == 0)
			return 0;
		if (ret == AVERROR_EOF || v->draining)
			return -ENODATA;
		/* EAGAIN, or an error that was one bad frame (dropped): the next packet. */
		ret = av_read_frame(v->fmt, v->pkt);
		if (ret == AVERROR(EAGAIN))
			continue;
		if (ret < 0) { /* the end, or the file broke off: what the decoder holds comes out */
			v->draining = true;
			avcodec_send_packet(v->dec, NULL);
			continue;
		}
		/* A packet the decoder refuses (corrupt) is skipped, as OpenCV's reader did. */
		if (v->pkt->stream_index == v->stream)
			(void)avcodec_send_packet(v->dec, v->pkt);
		av_packet_unref(v->pkt);
	}
}

int mvod_video_open(const char *path, struct mvod_video **out)
{
	/*
	 * FFmpeg's own lines ("File ended prematurely", a decoder's complaints) would go to stderr
	 * beside mvod's one-line reasons; OpenCV's reader silenced them the same way.
	 */
	av_log_set_level(AV_LOG_QUIET);
	struct mvod_video *v = calloc(1, sizeof(*v));
	if (!v)
		return -ENOMEM;
	int ret = open_stream(v, path);
	if (ret == 0)
		ret = open_decoder(v);
	if (ret == 0)
		ret = decode(v);
	v->primed = ret == 0;
	if (ret) {
		mvod_video_close(v);
		return ret;
	}
	/* Y' 16..235 to 0..255, rounded: what swscale's YUV -> BGR then BGR -> grey gave. */
	for (int y = 0; y < 256; y++) {
		long g = lround((y - 16) * 255.0 / 219.0);
		v->range[y] = (uint8_t)(g < 0 ? 0 : g > 255 ? 255 : g);
	}
	*out = v;
	return 0;
}

/*
 * The stream's average rate, else FFmpeg's guess; its frame count, else the duration (the
 * container's, else the stream's) times that rate. OpenCV 4.6's reader took r_frame_rate first,
 * which for a variable-rate file is its time base's (mkvideo's 20/200 ms file: 1000 fps, 6600
 * frames announced for 60; now 50 fps and 330); file.c's end-of-stream test compares times, so
 * either is right for it, and every constant-rate file measured gets the same figures.
 */
void mvod_video_props(struct mvod_video *v, struct mvod_source_info *info)
{
	*info = (struct mvod_source_info){0, 0, 0.0, -1, false, NAN, false, false};
	AVStream *st = v->fmt->streams[v->stream];
	info->width = v->w;
	info->height = v->h;
	double fps = av_q2d(st->avg_frame_rate);
	if (!(fps > 1e-6))
		fps = av_q2d(av_guess_frame_rate(v->fmt, st, NULL));
	info->fps = isfinite(fps) && fps > 1e-6 ? fps : 0.0;
	double n = (double)st->nb_frames;
	if (n < 1) {
		double sec = (double)v->fmt->duration / AV_TIME_BASE;
		if (!(sec > 1e-6) && st->duration != AV_NOPTS_VALUE)
			sec = (double)st->duration * av_q2d(st->time_base);
		n = floor(sec * info->fps + 0.5);
	}
	info->frames = n >= 1 && n < 1e15 ? (int64_t)n : -1;
}

/* True when plane 0 of f's format holds 8-bit luma, one byte a pixel (grey, planar YUV, NV12). */
static bool luma_plane(enum AVPixelFormat fmt)
{
	const AVPixFmtDescriptor *d = av_pix_fmt_desc_get(fmt);
	return d && !(d->flags & (AV_PIX_FMT_FLAG_RGB | AV_PIX_FMT_FLAG_PAL |
				  AV_PIX_FMT_FLAG_BAYER | AV_PIX_FMT_FLAG_FLOAT)) &&
	       d->comp[0].plane == 0 && d->comp[0].step == 1 && d->comp[0].offset == 0 &&
	       d->comp[0].shift == 0 && d->comp[0].depth == 8;
}

/* Y' in 16..235 (TV range): the YUV formats but the JPEG ones and frames flagged full range. */
static bool limited_range(const AVFrame *f)
{
	enum AVPixelFormat p = f->format;
	if (f->color_range == AVCOL_RANGE_JPEG || p == AV_PIX_FMT_GRAY8 ||
	    p == AV_PIX_FMT_YUVJ420P || p == AV_PIX_FMT_YUVJ422P || p == AV_PIX_FMT_YUVJ444P ||
	    p == AV_PIX_FMT_YUVJ440P || p == AV_PIX_FMT_YUVJ411P)
		return false;
	const AVPixFmtDescriptor *d = av_pix_fmt_desc_get(p);
	return d && d->nb_components >= 3;
}

/*
 * f as grey into v->grey (w x h, stride w): the luma copied (a bottom-up plane) or through the
 * range table (limited), or anything else through swscale.
 */
static int to_grey(struct mvod_video *v, const AVFrame *f, bool luma, bool limited)
{
	if (luma) {
		for (int y = 0; y < v->h; y++) {
			const uint8_t *in = f->data[0] + (ptrdiff_t)y * f->linesize[0];
			uint8_t *out = v->grey + (size_t)y * (size_t)v->w;
			if (!limited)
				memcpy(out, in, (size_t)v->w);
			for (int x = 0; limited && x < v->w; x++)
				out[x] = v->range[in[x]];
		}
		return 0;
	}
	/* Created for the first such frame and kept: the size and format do not change. */
	v->sws = sws_getCachedContext(v->sws, v->w, v->h, f->format, v->w, v->h,
				      AV_PIX_FMT_GRAY8, SWS_BICUBIC, NULL, NULL, NULL);
	if (!v->sws)
		return -ENOTSUP;
	uint8_t *dst[4] = {v->grey};
	int dst_stride[4] = {v->w};
	sws_scale(v->sws, (const uint8_t *const *)f->data, f->linesize, 0, v->h, dst, dst_stride);
	return 0;
}

int mvod_video_read(struct mvod_video *v, struct mvod_image *img, int64_t *media_us)
{
	int ret = 0;
	if (!v->primed) {
		av_frame_unref(v->frame);
		ret = decode(v);
	}
	v->primed = false;
	if (ret)
		return ret;
	const AVFrame *f = v->frame;
	int64_t pts = f->best_effort_timestamp;
	*media_us = pts == AV_NOPTS_VALUE ? 0 : av_rescale_q(pts - v->start, v->tb, AV_TIME_BASE_Q);
	*img = (struct mvod_image){.w = f->width, .h = f->height, .stride = f->linesize[0],
				   .fmt = MVOD_PIX_GREY, .data = NULL};
	if (f->width != v->w || f->height != v->h)
		return -EMSGSIZE;
	bool luma = luma_plane(f->format), limited = luma && limited_range(f);
	if (luma && !limited && f->linesize[0] > 0) {
		img->data = f->data[0]; /* the decoder's plane, as it is */
		return 0;
	}
	ret = to_grey(v, f, luma, limited);
	if (ret)
		return ret;
	img->stride = v->w;
	img->data = v->grey;
	return 0;
}
