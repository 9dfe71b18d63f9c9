/* col0rme report OUTDIR: report.html (and error_qNN.tif) again from an
 * output directory's files (report/html.h does the work). */
#include "cli/commands.h"
#include "cli/opts.h"
#include "col0rme.h"

#include <stdio.h>

int cmd_report(int argc, char **argv)
{
	const struct c0_cmd_spec spec = { "report", "OUTDIR",
		"Write OUTDIR/report.html from the files of an earlier run, support or intensity\n"
		"(report.json and the TIFFs): the mean images, the render, the depth map, the error\n"
		"map (also error_qNN.tif: the data's mean minus the estimate through the forward\n"
		"model), the lambda criterion, drift, bleaching and FRC curves, warnings, the\n"
		"parameters with their source, timings and the command that reproduces the run.\n"
		"One self-contained file. On error nothing is written.",
		NULL, 0, 1, 1, 0 };
	char *dir[1];
	int npos = 0, rc = c0_opts_parse(&spec, argc, argv, &npos, dir);
	if (rc)
		return rc == 1 ? 0 : 2;
	if (c0_report_html(dir[0]))
		return c0_cli_error("report");
	printf("report: %s/report.html\n", dir[0]);
	return 0;
}
