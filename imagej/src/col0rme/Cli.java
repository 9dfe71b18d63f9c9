package col0rme;

import ij.IJ;
import ij.Prefs;

import java.awt.Button;
import java.awt.Dialog;
import java.awt.FlowLayout;
import java.awt.Frame;
import java.awt.GraphicsEnvironment;
import java.awt.Label;
import java.io.File;
import java.io.IOException;
import java.io.InputStream;
import java.io.InputStreamReader;
import java.io.Reader;
import java.nio.charset.StandardCharsets;
import java.util.ArrayList;
import java.util.HashMap;
import java.util.List;
import java.util.Map;
import java.util.concurrent.TimeUnit;

/** The col0rme executable, run as a child process: found, asked for its
 *  options (--help-json), and run with its progress on ImageJ's status line
 *  and progress bar (from --progress-json: the library's progress callback,
 *  one JSON line per call on stderr, cli/cmdkit.c); Escape or Cancel ends
 *  it (SIGTERM: the CLI removes its staging directory, so no partial output
 *  folder is left). */
final class Cli {
	static final String PREF = "col0rme.executable";
	private static final Map<String, Map<String, Map<String, Object>>> helpCache = new HashMap<String, Map<String, Map<String, Object>>>();
	/* the stages the last run with progress finished, in order, as its JSON lines told them (read by the tests) */
	static volatile String stagesDone = "";

	final String exe;

	private Cli(String exe) { this.exe = exe; }

	/** In this order: the path kept in ImageJ's preferences, PATH, the
	 *  install prefix next to this jar (PREFIX/share/col0rme/imagej). */
	static Cli locate() throws Failure {
		String set = Prefs.get(PREF, "");
		if (!set.isEmpty()) {
			if (new File(set).canExecute())
				return new Cli(set);
			throw new Failure("col0rme: the executable set in ImageJ's preferences (" + set
				+ ") does not exist or cannot be run: fix it with Plugins > col0rme > Set col0rme executable...");
		}
		String path = System.getenv("PATH");
		if (path != null)
			for (String d : path.split(File.pathSeparator)) {
				File f = new File(d.isEmpty() ? "." : d, "col0rme");
				if (f.isFile() && f.canExecute())
					return new Cli(f.getAbsolutePath());
			}
		File prefix = prefixBin();
		if (prefix != null && prefix.canExecute())
			return new Cli(prefix.getAbsolutePath());
		throw new Failure("col0rme: the col0rme executable was not found (ImageJ's preferences, PATH"
			+ (prefix != null ? ", " + prefix : "") + "): install col0rme or set it with Plugins > col0rme > Set col0rme executable...");
	}

	private static File prefixBin() {
		try {
			File dir = new File(Cli.class.getProtectionDomain().getCodeSource().getLocation().toURI()).getParentFile();
			if (!dir.getPath().endsWith("share" + File.separator + "col0rme" + File.separator + "imagej"))
				return null;   /* not installed by cmake --install */
			return new File(dir.getParentFile().getParentFile().getParentFile(), "bin" + File.separator + "col0rme");
		} catch (Exception e) {
			return null;
		}
	}

	/** The options of one subcommand, by flag ("--fwhm"), as the CLI prints them. */
	Map<String, Map<String, Object>> options(String command) throws Failure {
		String key = exe + " " + command;
		Map<String, Map<String, Object>> m = helpCache.get(key);
		if (m != null)
			return m;
		List<String> args = new ArrayList<String>();
		args.add(command);
		args.add("--help-json");
		String out = run(args, false);
		m = new HashMap<String, Map<String, Object>>();
		try {
			@SuppressWarnings("unchecked")
			Map<String, Object> doc = (Map<String, Object>) Json.parse(out);
			@SuppressWarnings("unchecked")
			List<Object> opts = (List<Object>) doc.get("options");
			for (Object o : opts) {
				@SuppressWarnings("unchecked")
				Map<String, Object> row = (Map<String, Object>) o;
				m.put((String) row.get("flag"), row);
			}
		} catch (RuntimeException e) {
			throw new Failure("col0rme: " + exe + " " + command + " --help-json did not print its options (" + e.getMessage()
				+ "): is it col0rme 0.1 or newer?");
		}
		helpCache.put(key, m);
		return m;
	}

	/** Runs col0rme with args; returns its standard output. With progress
	 *  set, --progress-json is passed and its lines drive the status line;
	 *  a non-zero exit throws the CLI's error line. */
	String run(List<String> args, boolean progress) throws Failure {
		List<String> cmd = new ArrayList<String>();
		cmd.add(exe);
		cmd.addAll(args);
		if (progress) {
			cmd.add(2, "--progress-json");   /* after the subcommand: one of its flags */
			stagesDone = "";
		}
		final Process p;
		try {
			p = new ProcessBuilder(cmd).start();
		} catch (IOException e) {
			throw new Failure("col0rme: cannot run " + exe + ": " + e.getMessage());
		}
		final StringBuilder out = new StringBuilder();
		final List<String> errLines = new ArrayList<String>();
		Thread to = drain(p.getInputStream(), out, null, false);
		Thread te = drain(p.getErrorStream(), null, errLines, progress);
		CancelWindow cw = progress ? CancelWindow.open(args.get(0)) : null;
		IJ.resetEscape();
		boolean cancelled = false;
		try {
			while (!p.waitFor(100, TimeUnit.MILLISECONDS))
				if (IJ.escapePressed() || (cw != null && cw.pressed)) {
					cancelled = true;
					p.destroy();   /* SIGTERM: the CLI rolls its output back */
					if (!p.waitFor(20, TimeUnit.SECONDS))
						p.destroyForcibly().waitFor();
					break;
				}
			to.join();
			te.join();
		} catch (InterruptedException e) {
			p.destroy();
			Thread.currentThread().interrupt();
			throw new Failure("col0rme: interrupted", true);
		} finally {
			if (cw != null)
				cw.dispose();
			if (progress) {
				IJ.showProgress(1.0);
				IJ.showStatus("");
			}
		}
		if (cancelled)
			throw new Failure("col0rme " + args.get(0) + ": cancelled; nothing was written", true);
		if (p.exitValue() != 0) {
			String line = null;
			for (String l : errLines)
				if (l.contains(": error:"))
					line = l;
			if (line == null)
				line = "col0rme " + args.get(0) + ": exited with status " + p.exitValue()
					+ (errLines.isEmpty() ? "" : ": " + errLines.get(errLines.size() - 1));
			throw new Failure(line.trim());
		}
		return out.toString();
	}

	/* Reads a stream to its end on its own thread: into out, or as lines
	 * into lines and the status. */
	private static Thread drain(final InputStream in, final StringBuilder out, final List<String> lines, final boolean progress) {
		Thread t = new Thread(new Runnable() {
			public void run() {
				StringBuilder line = new StringBuilder();
				try (Reader r = new InputStreamReader(in, StandardCharsets.UTF_8)) {
					char[] buf = new char[4096];
					for (int n; (n = r.read(buf)) > 0;) {
						if (out != null) {
							synchronized (out) { out.append(buf, 0, n); }
							continue;
						}
						for (int i = 0; i < n; i++) {
							char c = buf[i];
							if (c != '\r' && c != '\n') {
								line.append(c);
								continue;
							}
							take(line.toString(), lines, progress);
							line.setLength(0);
						}
					}
					take(line.toString(), lines, progress);
				} catch (IOException e) {
					/* the process ended */
				}
			}
		}, "col0rme output");
		t.start();
		return t;
	}

	private static void take(String l, List<String> lines, boolean progress) {
		if (l.trim().isEmpty())
			return;
		if (l.startsWith("{\"progress\":")) {
			if (progress)
				show(l);
			return;
		}
		synchronized (lines) { lines.add(l); }
	}

	/* {"progress":{"stage":S,"fraction":F,"seconds":T}}: the bar, the status
	 * line (percent, and an ETA once it can be guessed) */
	private static void show(String l) {
		String stage;
		double f, t;
		try {
			@SuppressWarnings("unchecked")
			Map<String, Object> p = (Map<String, Object>) ((Map<String, Object>) Json.parse(l)).get("progress");
			stage = (String) p.get("stage");
			f = ((Double) p.get("fraction")).doubleValue();
			t = ((Double) p.get("seconds")).doubleValue();
		} catch (RuntimeException e) {
			return;   /* not ours: a newer CLI's line */
		}
		IJ.showProgress(f);
		IJ.showStatus("col0rme: " + stage + " " + Math.round(100 * f) + "%"
			+ (f > 0.01 && f < 1 ? String.format(java.util.Locale.ROOT, ", ETA %.1f s", t * (1 - f) / f) : "") + " (Esc cancels)");
		if (f >= 1)
			stagesDone = stagesDone.isEmpty() ? stage : stagesDone + " " + stage;
	}

	/** A small window with a Cancel button while the child runs (not in batch mode). */
	static final class CancelWindow extends Dialog {
		private static final long serialVersionUID = 1L;
		volatile boolean pressed;

		private CancelWindow(Frame owner, String what) {
			super(owner, "col0rme " + what, false);
			setLayout(new FlowLayout());
			add(new Label("col0rme " + what + " is running (Esc or Cancel ends it)"));
			Button b = new Button("Cancel");
			b.addActionListener(e -> pressed = true);
			add(b);
			pack();
		}

		static CancelWindow open(String what) {
			if (GraphicsEnvironment.isHeadless() || IJ.getInstance() == null || ij.macro.Interpreter.isBatchMode())
				return null;
			CancelWindow w = new CancelWindow(IJ.getInstance(), what);
			w.setVisible(true);
			return w;
		}
	}
}
