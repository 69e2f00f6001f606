#include "capture/video_size.h"

#include <errno.h>
#include <stdlib.h>

#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>

struct mvod_vsize {
	AVFormatContext *fmt;
	AVCodecContext *ctx; /* the parser's scratch; no decoder is opened */
	AVCodecParserContext *parser;
	AVPacket *pkt;       /* reused for every packet */
	int stream;
};

void mvod_vsize_close(struct mvod_vsize *v)
{
	if (!v)
		return;
	av_packet_free(&v->pkt);
	if (v->parser)
		av_parser_close(v->parser);
	avcodec_free_context(&v->ctx);
	avformat_close_input(&v->fmt);
	free(v);
}

static int open_stream(struct mvod_vsize *v, const char *path)
{
	if (avformat_open_input(&v->fmt, path, NULL, NULL) < 0)
		return -EINVAL;
	v->stream = av_find_best_stream(v->fmt, AVMEDIA_TYPE_VIDEO, -1, -1, NULL, 0);
	if (v->stream < 0)
		return -EINVAL;
	enum AVCodecID id = v->fmt->streams[v->stream]->codecpar->codec_id;
	v->parser = av_parser_init((int)id);
	if (!v->parser)
		return -ENOTSUP;
	/* Demuxed packets are whole frames: the parser must not wait for the next to end one. */
	v->parser->flags |= PARSER_FLAG_COMPLETE_FRAMES;
	v->ctx = avcodec_alloc_context3(NULL);
	v->pkt = av_packet_alloc();
	return v->ctx && v->pkt ? 0 : -ENOMEM;
}

int mvod_vsize_open(const char *path, struct mvod_vsize **out)
{
	struct mvod_vsize *v = calloc(1, sizeof(*v));
	if (!v)
		return -ENOMEM;
	int ret = open_stream(v, path);
	if (ret) {
		mvod_vsize_close(v);
		return ret;
	}
	*out = v;
	return 0;
}

int mvod_vsize_next(struct mvod_vsize *v, int *w, int *h)
{
	for (;;) {
		int ret = av_read_frame(v->fmt, v->pkt);
		if (ret == AVERROR_EOF)
			return -ENODATA;
		if (ret < 0)
			return -EIO;
		if (v->pkt->stream_index != v->stream) {
			av_packet_unref(v->pkt);
			continue;
		}
		uint8_t *data;
		int size;
		av_parser_parse2(v->parser, v->ctx, &data, &size, v->pkt->data, v->pkt->size,
				 v->pkt->pts, v->pkt->dts, v->pkt->pos);
		av_packet_unref(v->pkt);
		*w = v->parser->width;
		*h = v->parser->height;
		return 0;
	}
}
