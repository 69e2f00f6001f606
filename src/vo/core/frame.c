#include "frame.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static int slot_init(struct mvod_vo_frame *k, int cap, int desc_bytes)
{
	k->f.cap = cap;
	k->f.desc_bytes = desc_bytes;
	k->f.kp = calloc((size_t)cap, sizeof(*k->f.kp));
	k->f.desc = calloc((size_t)cap, (size_t)desc_bytes);
	k->pts = calloc((size_t)cap * 3, sizeof(double));
	k->has_pt = calloc((size_t)cap, 1);
	k->par = calloc((size_t)cap, sizeof(float));
	k->pt = calloc((size_t)cap, sizeof(*k->pt));
	k->first = calloc((size_t)cap, sizeof(*k->first));
	k->odo = NAN;
	return k->f.kp && k->f.desc && k->pts && k->has_pt && k->par && k->pt && k->first
		       ? 0
		       : -ENOMEM;
}

static void slot_fini(struct mvod_vo_frame *k)
{
	free(k->f.kp);
	free(k->f.desc);
	free(k->pts);
	free(k->has_pt);
	free(k->par);
	free(k->pt);
	free(k->first);
}

int mvod_frames_init(struct mvod_frames *fr, int cap, int desc_bytes)
{
	*fr = (struct mvod_frames){.cap = cap};
	fr->ref = &fr->slot[0];
	fr->cur = &fr->slot[1];
	fr->matches = calloc((size_t)cap, sizeof(*fr->matches));
	if (!fr->matches)
		return -ENOMEM;
	for (int i = 0; i < 2; i++)
		if (slot_init(&fr->slot[i], cap, desc_bytes))
			return -ENOMEM;
	return 0;
}

void mvod_frames_fini(struct mvod_frames *fr)
{
	for (int i = 0; i < 2; i++)
		slot_fini(&fr->slot[i]);
	free(fr->matches);
}

void mvod_frames_begin(struct mvod_frames *fr)
{
	fr->cur->seq = fr->count++;
	fr->cur->has_par = 0; /* until a two-view step writes its parallax */
	fr->n_matches = 0;
}

void mvod_frames_promote(struct mvod_frames *fr, const struct mvod_pose *pose, const double *gt,
			 bool with_structure)
{
	if (!with_structure) {
		memset(fr->cur->has_pt, 0, (size_t)fr->cur->f.n);
		fr->cur->has_par = 0;
	}
	struct mvod_vo_frame *k = fr->ref;
	fr->ref = fr->cur;
	fr->cur = k;
	fr->ref->pose = *pose;
	if (gt)
		memcpy(fr->ref->gt, gt, sizeof(fr->ref->gt));
	fr->have_ref = true;
}

void mvod_frames_scale_ref(struct mvod_frames *fr, double f)
{
	for (int k = 0; k < 3; k++)
		fr->ref->pose.t[k] *= f;
}

double mvod_frames_gt_step(const struct mvod_frames *fr, const double gt[3])
{
	return mvod_vec3_dist(gt, fr->ref->gt);
}
