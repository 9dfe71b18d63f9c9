package col0rme;

import ij.Macro;
import ij.Prefs;
import ij.gui.GenericDialog;

import java.util.ArrayList;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

/** A dialog's fields. The ones that stand for a CLI option take their help
 *  and default from `col0rme CMD --help-json`; the label's first word is the
 *  macro key (GenericDialog's rule), so each field is a macro option. Shown
 *  as a GenericDialog (which reads and records macro options itself) or, with
 *  no display, read from an options string with the same keys. */
final class Fields {
	enum Kind { STRING, CHOICE, DIRECTORY, MESSAGE }

	static final class Field {
		Kind kind;
		String key, label, value, flag, help, cliDefault;
		String[] items;
		boolean fromImage;   /* value taken from the open images (calibration, properties) */
		boolean remembered = true;   /* its last value is kept in ImageJ's preferences */
	}

	private final Map<String, Map<String, Object>> cli;
	final List<Field> list = new ArrayList<Field>();

	Fields(Map<String, Map<String, Object>> cliOptions) { this.cli = cliOptions; }

	/** A field for the CLI option flag; prefill (may be null) wins over the
	 *  CLI's default, which is used when it is a value (not a description). */
	Field option(String label, String flag, String prefill) {
		Map<String, Object> o = cli.get(flag);
		if (o == null)
			throw new IllegalStateException("col0rme has no option " + flag);
		Field f = add(Kind.STRING, label, null);
		f.flag = flag;
		f.help = (String) o.get("help");
		f.cliDefault = (String) o.get("default");
		String mv = (String) o.get("metavar");
		if (mv != null && mv.matches("[a-z0-9]+(\\|[a-z0-9]+)+")) {
			f.kind = Kind.CHOICE;
			f.items = mv.split("\\|");
		}
		f.value = prefill != null ? prefill : isValue(f) ? f.cliDefault : "";
		f.fromImage = prefill != null;
		return f;
	}

	Field add(Kind kind, String label, String value) {
		Field f = new Field();
		f.kind = kind;
		f.label = label;
		f.key = Macro.trimKey(label);
		f.value = value;
		list.add(f);
		return f;
	}

	private static boolean isValue(Field f) {
		String d = f.cliDefault;
		if (d == null)
			return false;
		if (f.items != null)
			for (String s : f.items)
				if (s.equals(d))
					return true;
		return d.matches("[-+0-9.eE]+(,[-+0-9.eE]+)*");
	}

	/** The dialog; false when cancelled. Values are read back into the fields. */
	boolean ask(String title) {
		GenericDialog gd = new GenericDialog(title);
		for (Field f : list)
			switch (f.kind) {
			case STRING: gd.addStringField(f.label, f.value, 24); break;
			case DIRECTORY: gd.addDirectoryField(f.label, f.value, 24); break;
			case CHOICE: gd.addChoice(f.label, f.items, f.value); break;
			case MESSAGE: gd.addMessage(f.label); break;
			}
		gd.addMessage(emptyMeans());
		gd.addHelp(helpHtml(title));
		gd.showDialog();
		if (gd.wasCanceled())
			return false;
		for (Field f : list)
			switch (f.kind) {
			case STRING: case DIRECTORY: f.value = gd.getNextString().trim(); break;
			case CHOICE: f.value = gd.getNextChoice(); break;
			default: break;
			}
		return true;
	}

	/** The dialog's last values (ImageJ's preferences, keys prefix + macro
	 *  key) into the fields that hold neither a value from the images nor
	 *  one of the fields not remembered (the stacks, a new output folder). */
	void recall(String prefix) {
		for (Field f : list) {
			String v = f.kind == Kind.MESSAGE || f.fromImage || !f.remembered ? null : Prefs.get(prefix + f.key, null);
			if (v != null && (f.kind != Kind.CHOICE || java.util.Arrays.asList(f.items).contains(v)))
				f.value = v;
		}
	}

	/** Keeps the fields' values for the next dialog. */
	void remember(String prefix) {
		for (Field f : list)
			if (f.kind != Kind.MESSAGE && f.remembered && !f.fromImage)
				Prefs.set(prefix + f.key, f.value);
		Prefs.savePreferences();
	}

	/** The "other options" text as col0rme arguments: each flag checked
	 *  against the command's options (--help-json); one the command does not
	 *  have, one a field of the dialog gives, the output's and a value left
	 *  out are refused. */
	List<String> other(String text, String cmd) throws Failure {
		List<String> a = new ArrayList<String>();
		String[] t = text.trim().isEmpty() ? new String[0] : text.trim().split("\\s+");
		for (int i = 0; i < t.length; i++) {
			String flag = t[i].replaceAll("=.*", "");
			Map<String, Object> o = cli.get(flag);
			if (o == null)
				for (Map<String, Object> r : cli.values())
					if (flag.equals(r.get("short")))
						o = r;
			if (o == null || !flag.startsWith("-"))
				throw new Failure("col0rme: other options: " + t[i] + " is not an option of col0rme " + cmd
					+ " (col0rme " + cmd + " --help lists them)");
			String f = (String) o.get("flag");
			for (Field d : list)
				if (f.equals(d.flag))
					throw new Failure("col0rme: other options: " + f + " is the dialog's field " + d.key + "=: give it there");
			if (f.equals("--output") || f.equals("--force") || f.equals("--verbose") || f.equals("--progress-json"))
				throw new Failure("col0rme: other options: " + f + " is the plugin's own (the output folder is the dialog's field)");
			a.add(t[i]);
			if (!"flag".equals(o.get("type")) && !t[i].contains("=")) {
				if (i + 1 == t.length)
					throw new Failure("col0rme: other options: " + f + " needs a value (" + o.get("metavar") + ")");
				a.add(t[++i]);
			}
		}
		return a;
	}

	/** No display: the same keys read from a macro options string. */
	void read(String options) throws Failure {
		String opts = options.trim() + " ";
		for (Field f : list) {
			if (f.kind == Kind.MESSAGE)
				continue;
			f.value = Macro.getValue(opts, f.key, f.value).trim();
			if (f.kind == Kind.CHOICE && !java.util.Arrays.asList(f.items).contains(f.value))
				throw new Failure("col0rme: " + f.key + "=" + f.value + ": expected one of " + String.join(", ", f.items));
		}
	}

	Field get(String key) {
		for (Field f : list)
			if (key.equals(f.key))
				return f;
		throw new IllegalStateException(key);
	}

	/** The CLI arguments of the option fields whose value differs from the
	 *  CLI's default (an empty field leaves the CLI's default). */
	List<String> args() {
		List<String> a = new ArrayList<String>();
		for (Field f : list)
			if (f.flag != null && !f.value.isEmpty() && !f.value.equals(f.cliDefault)) {
				a.add(f.flag);
				a.add(f.value);
			}
		return a;
	}

	/* What an empty field means, in the CLI's words (its default text up to
	 * the first colon: "automatic: max(...)" reads "automatic"). */
	private String emptyMeans() {
		StringBuilder b = new StringBuilder("An empty field leaves col0rme's default (Help lists them all):");
		for (Field f : list)
			if (f.flag != null && f.cliDefault != null && !isValue(f) && !f.cliDefault.equals("none"))
				b.append("\n    ").append(f.label.replaceAll(" \\(.*", "")).append(": ").append(f.cliDefault.replaceAll(":.*", ""));
		return b.toString();
	}

	private String helpHtml(String title) {
		StringBuilder b = new StringBuilder("<html><h2>" + esc(title) + "</h2><table border=1 cellpadding=3>");
		b.append("<tr><th>field (macro key)</th><th>col0rme option</th><th>meaning</th><th>default</th></tr>");
		for (Field f : list)
			if (f.kind != Kind.MESSAGE)
				b.append("<tr><td>").append(esc(f.label)).append(" (").append(f.key).append(")</td><td>")
					.append(f.flag != null ? f.flag : "").append("</td><td>").append(esc(f.help))
					.append("</td><td>").append(esc(f.cliDefault != null ? f.cliDefault : "")).append("</td></tr>");
		return b.append("</table><p>An empty field leaves col0rme's default.</p></html>").toString();
	}

	private static String esc(String s) {
		return s == null ? "" : s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;");
	}

	static Map<String, String> values(Fields fs) {
		Map<String, String> m = new LinkedHashMap<String, String>();
		for (Field f : fs.list)
			if (f.kind != Kind.MESSAGE)
				m.put(f.key, f.value);
		return m;
	}
}
