#include "tracked.h"

#include <string.h>

void mvod_tracked_start(struct mvod_tracked *c, const double Ra[9], const double ta[3],
			const double Rb[9], const double tb[3])
{
	memcpy(c->Rcw, Rb, sizeof(c->Rcw));
	memcpy(c->tcw, tb, sizeof(c->tcw));
	mvod_motion_between(Ra, ta, Rb, tb, c->vR, c->vt);
}

void mvod_tracked_set(struct mvod_tracked *c, const double R[9], const double t[3])
{
	mvod_motion_between(c->Rcw, c->tcw, R, t, c->vR, c->vt);
	mvod_tracked_place(c, R, t);
}

void mvod_tracked_place(struct mvod_tracked *c, const double R[9], const double t[3])
{
	memcpy(c->Rcw, R, sizeof(c->Rcw));
	memcpy(c->tcw, t, sizeof(c->tcw));
}

void mvod_tracked_follow(struct mvod_tracked *c, const double Rk[9], const double tk[3],
			 const double R[9], const double t[3])
{
	double C[9], d[3], dc[3];
	mvod_mat3_mul_bt(c->Rcw, Rk, C);
	mvod_mat3_mul(C, R, c->Rcw);
	for (int i = 0; i < 3; i++)
		d[i] = t[i] - tk[i];
	mvod_mat3_vec(C, d, dc);
	for (int i = 0; i < 3; i++)
		c->tcw[i] += dc[i];
}

void mvod_tracked_rescale(struct mvod_tracked *c, const double centre[3], double s)
{
	mvod_rigid_scale(c->Rcw, c->tcw, centre, s);
	for (int k = 0; k < 3; k++)
		c->vt[k] *= s;
}

void mvod_tracked_predict(const struct mvod_tracked *c, double R[9], double t[3])
{
	mvod_mat3_mul(c->vR, c->Rcw, R);
	mvod_rigid_apply(c->vR, c->vt, c->tcw, t);
}

double mvod_tracked_speed(const struct mvod_tracked *c)
{
	return mvod_vec3_norm(c->vt);
}

void mvod_tracked_pose(const struct mvod_tracked *c, struct mvod_pose *c2w)
{
	memcpy(c2w->R, c->Rcw, sizeof(c2w->R));
	memcpy(c2w->t, c->tcw, sizeof(c2w->t));
	mvod_pose_inverse(c2w, c2w);
}
