#include "util/numbers.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int mvod_parse_numbers(const char *s, double *v, int max)
{
	int n = 0;
	for (char *end;; s = end) {
		s += strspn(s, " \t");
		if (!*s)
			return n;
		double x = strtod(s, &end);
		if (end == s || !isfinite(x) || n == max || (*end && *end != ' ' && *end != '\t'))
			return -1;
		v[n++] = x;
	}
}
