/*
 * version.h - the one version string of trajd's programs and library.
 *
 * Every program prints it for --version ("PROGRAM VERSION"); the Makefile reads
 * it from here for trajd.pc and the man pages, so the three cannot differ.
 */
#ifndef TRAJD_VERSION_H
#define TRAJD_VERSION_H

#define TRAJD_VERSION "0.1"

#endif
