/* Lines of plain numbers, as KITTI's calibration and OXTS files and DSO's camera.txt hold them. */
#ifndef MVOD_UTIL_NUMBERS_H
#define MVOD_UTIL_NUMBERS_H

/*
 * Up to max finite numbers at s, each after spaces or tabs, to the end of s into v: how many,
 * or -1 when anything else is there (a word, NaN or infinity, a number too many).
 */
int mvod_parse_numbers(const char *s, double *v, int max);

#endif
