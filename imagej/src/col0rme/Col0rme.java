package col0rme;

import ij.IJ;
import ij.ImagePlus;
import ij.Macro;
import ij.Prefs;
import ij.WindowManager;
import ij.gui.GenericDialog;
import ij.macro.Interpreter;
import ij.plugin.PlugIn;

import java.awt.GraphicsEnvironment;
import java.io.File;
import java.nio.file.Files;
import java.util.ArrayList;
import java.util.List;
import java.util.Map;

/** Plugins > col0rme: 3D-COL0RME..., Support only..., Demo data and Set
 *  col0rme executable... (plugins.config). The static methods run3d, support
 *  and demo are the same commands for macros with no display:
 *  call("col0rme.Col0rme.run3d", "angles=... pixel=100 fwhm=229 output=...").
 *  Every error is one line: IJ.error in ImageJ's window; with no window it
 *  goes to stderr. Either way the macro that asked ends there (a macro
 *  error), and a script that calls these methods outside a macro gets a
 *  RuntimeException with the line: Java itself never ends. */
public class Col0rme implements PlugIn {
	static final String RUN = "3D-COL0RME", SUPPORT = "col0rme support";
	/** The demo acquisition's incidence angles (degrees in the glass). */
	static final String DEMO_ANGLES = "62.5,63.5,65,67,70";

	@Override
	public void run(String arg) {
		try {
			switch (arg) {
			case "run": method(true, null); break;
			case "support": method(false, null); break;
			case "demo": demoData(null); break;
			case "locate": locateDialog(); break;
			default: throw new Failure("col0rme: unknown command " + arg);
			}
		} catch (Failure e) {
			fail(e);
		}
	}

	/** 3D-COL0RME with no display; returns the output folder. */
	public static String run3d(String options) { return batch(true, options); }

	/** col0rme support with no display; returns the output folder. */
	public static String support(String options) { return batch(false, options); }

	/** Demo data with no display, into dir (a new temporary folder when empty); returns it. */
	public static String demo(String dir) {
		try {
			return demoData(dir == null || dir.isEmpty() ? null : new File(dir)).getPath();
		} catch (Failure e) {
			fail(e);
			return "";
		}
	}

	private static String batch(boolean whole, String options) {
		try {
			return method(whole, options == null ? "" : options).getPath();
		} catch (Failure e) {
			fail(e);
			return "";
		}
	}

	static void fail(Failure e) {
		String line = e.getMessage();
		if (GraphicsEnvironment.isHeadless() || IJ.getInstance() == null) {
			if (Interpreter.getInstance() == null)
				throw new RuntimeException(line, e);   /* a script (Groovy, Jython...) catches it */
			System.err.println(line);
			System.err.flush();
			Interpreter.abort();   /* the macro ends here; ImageJ goes on */
			return;
		}
		if (e.cancelled)
			IJ.showStatus(line);
		else
			IJ.error("col0rme", line);
		if (IJ.isMacro())
			Macro.abort();   /* a macro does not go on without the result */
	}

	/* The dialog (or options), the checks, the run and the results. options:
	 * null for a dialog (which reads macro options itself), else the options
	 * of a call with no display. */
	private static File method(boolean whole, String options) throws Failure {
		Cli cli = Cli.locate();
		String cmd = whole ? "run" : "support";
		Fields fs = new Fields(cli.options(cmd));
		String stacks = Inputs.openStacks();
		if (!whole) {
			ImagePlus cur = WindowManager.getCurrentImage();
			stacks = cur != null ? cur.getTitle() : stacks.split(",")[0];
		}
		Inputs pre = null;
		try {
			pre = stacks.isEmpty() ? null : Inputs.pick(stacks);
		} catch (Failure e) {
			/* the user picks other titles in the dialog */
		}
		fs.add(Fields.Kind.STRING, whole ? "Stacks (one per angle, or one hyperstack)" : "Stack", stacks);
		if (whole)
			fs.option("Angles (deg)", "--angles", property(pre, "col0rme.angles", true));
		fs.option("Pixel size (nm)", "--pixel-size", pre != null ? pre.calibratedPixelNm() : null);
		fs.option("FWHM (nm)", "--fwhm", property(pre, "col0rme.fwhm", false));
		fs.option("NA (instead of FWHM, with emission)", "--na", null);
		fs.option("Emission (nm)", "--emission", null);
		if (whole) {
			fs.option("Glass index", "--n-glass", null);
			fs.option("Sample index", "--n-sample", null);
			fs.option("Wavelength (nm, excitation)", "--wavelength", null);
		}
		fs.add(Fields.Kind.STRING, "Frames (first-last; empty: all)", "").help =
			"only these frames of every stack (1-based, e.g. 1-500); a rectangular selection on a stack crops them all";
		fs.add(Fields.Kind.DIRECTORY, "Output folder (new)", defaultOutput(pre, cmd)).remembered = false;
		fs.get("output").help = (String) cli.options(cmd).get("--output").get("help");
		fs.get(whole ? "stacks" : "stack").remembered = false;
		fs.add(Fields.Kind.MESSAGE, "Advanced", null);
		fs.option("Lambda", "--lambda", null);
		fs.option("Penalty", "--penalty", null);
		fs.option("Drift correction", "--drift", null);
		if (whole)
			fs.option("Bleaching correction", "--bleach", null);
		fs.add(Fields.Kind.STRING, "Other options (col0rme " + cmd + " flags)", "").help =
			"any other option of col0rme " + cmd + ", as on its command line (e.g. --acquisition interleaved --gains 1,1.05,1.1); "
			+ "checked against col0rme " + cmd + " --help-json";
		if (options == null) {
			String prefs = "col0rme." + cmd + ".";
			if (Macro.getOptions() == null)
				fs.recall(prefs);   /* a macro gives its own values: it stays reproducible */
			if (!fs.ask(whole ? "3D-COL0RME" : "col0rme support"))
				throw new Failure("col0rme: cancelled", true);
			if (Macro.getOptions() == null)
				fs.remember(prefs);
		} else
			fs.read(options);
		return execute(cli, cmd, fs, whole);
	}

	private static File execute(Cli cli, String cmd, Fields fs, boolean whole) throws Failure {
		Inputs in = Inputs.pick(fs.get(whole ? "stacks" : "stack").value);
		if (!whole && in.count() != 1)
			throw new Failure("col0rme support: give one stack (stack=TITLE)");
		if (whole) {
			String a = fs.get("angles").value;
			in.checkCount(a.isEmpty() ? 0 : a.split(",").length);
		}
		if (fs.get("pixel").value.isEmpty())
			in.checkCalibrated();
		String out = fs.get("output").value;
		if (out.isEmpty())
			throw new Failure("col0rme: give an output folder (output=DIR)");
		File outdir = new File(out).getAbsoluteFile();
		String[] existing = outdir.list();
		if (existing != null && existing.length > 0)
			throw new Failure("col0rme: output folder " + outdir + " is not empty: give a new one");
		List<String> args = new ArrayList<String>();
		args.add(cmd);
		args.add("-o");
		args.add(outdir.getPath());
		args.addAll(fs.args());
		args.addAll(fs.other(fs.get("other").value, cmd));
		try {
			String cut = in.restrict(fs.get("frames").value);
			if (!cut.isEmpty())
				IJ.log("col0rme: the stacks restricted to " + cut);
			in.write();
			args.addAll(in.paths);
			IJ.log("col0rme: " + cli.exe + " " + String.join(" ", args));
			cli.run(args, true);
		} finally {
			in.close();
		}
		Results.open(outdir);
		return outdir;
	}

	/* A property every picked stack carries (the demo's): the stacks' values
	 * joined by commas (angles), or the first stack's. */
	private static String property(Inputs in, String key, boolean join) {
		if (in == null)
			return null;
		StringBuilder b = new StringBuilder();
		for (ImagePlus imp : in.images) {
			Object v = imp.getProperty(key);
			if (v == null)
				return null;
			if (b.length() == 0 || join)
				b.append(b.length() > 0 ? "," : "").append(v);
		}
		return b.toString();
	}

	/* FIRST_DIR/col0rme_run (or _2, _3...): a new folder beside the first stack. */
	private static String defaultOutput(Inputs in, String cmd) {
		File dir = null;
		if (in != null && in.images.get(0).getOriginalFileInfo() != null && in.images.get(0).getOriginalFileInfo().directory != null)
			dir = new File(in.images.get(0).getOriginalFileInfo().directory);
		if (dir == null || !dir.canWrite())
			dir = new File(System.getProperty("user.home"), "col0rme");
		File f = new File(dir, "col0rme_" + cmd);
		for (int k = 2; f.exists(); k++)
			f = new File(dir, "col0rme_" + cmd + "_" + k);
		return f.getPath();
	}

	/* col0rme simulate with its defaults and the demo's angles: five 64x64
	 * stacks of 500 frames, opened with the angles and the FWHM they were
	 * simulated with, so the 3D-COL0RME dialog is filled in. */
	static File demoData(File dir) throws Failure {
		Cli cli = Cli.locate();
		Map<String, Object> fwhm = cli.options("simulate").get("--fwhm");
		try {
			if (dir == null)
				dir = Files.createTempDirectory("col0rme-demo").toFile();
			else
				Files.createDirectories(dir.toPath());
		} catch (java.io.IOException e) {
			throw new Failure("col0rme: cannot create a temporary folder: " + e.getMessage());
		}
		File data = new File(dir, "data");
		List<String> args = new ArrayList<String>();
		args.add("simulate");
		args.add("--angles");
		args.add(DEMO_ANGLES);
		args.add("-o");
		args.add(data.getPath());
		cli.run(args, true);
		String[] angles = DEMO_ANGLES.split(",");
		for (int i = 0; i < angles.length; i++) {
			ImagePlus imp = IJ.openImage(new File(data, String.format("stack_q%02d.tif", i + 1)).getPath());
			if (imp == null)
				throw new Failure("col0rme: simulate wrote no stack_q" + (i + 1) + " in " + data);
			imp.setProperty("col0rme.angles", angles[i]);
			imp.setProperty("col0rme.fwhm", fwhm.get("default"));
			imp.show();
		}
		IJ.log("col0rme: demo data in " + data + " (angles " + DEMO_ANGLES + " deg); now Plugins > col0rme > 3D-COL0RME...");
		return dir;
	}

	private static void locateDialog() {
		GenericDialog gd = new GenericDialog("col0rme executable");
		gd.addFileField("col0rme", Prefs.get(Cli.PREF, ""), 36);
		gd.addMessage("Empty: look on PATH, then next to this plugin's install prefix.");
		gd.showDialog();
		if (gd.wasCanceled())
			return;
		Prefs.set(Cli.PREF, gd.getNextString().trim());
		Prefs.savePreferences();
	}
}
