/*
 * csv_tail.h - the columns an existing CSV output ends with, so that a start
 * or a reload that appends with other columns (csv.geo, csv.age turned on or
 * off) writes a new header line first (issue 24): every row then sits under a
 * header with its own columns.  The four column sets have distinct field
 * counts (16, 17 with age_s, 20 with the geo columns, 21 with both), so the
 * count of the last line that is not a comment tells them apart.
 */
#ifndef TRAJD_CSV_TAIL_H
#define TRAJD_CSV_TAIL_H

/* Fields of the last line of the file at path that is neither empty nor a
 * "#" comment (a row or a header), looking at its last CSV_TAIL_BYTES; 0 if
 * there is none, the file cannot be read, or no whole line fits. */
int csv_tail_fields(const char *path);

#define CSV_TAIL_BYTES 8192

#endif
