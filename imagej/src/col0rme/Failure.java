package col0rme;

/** One line for the user: the CLI's error, or what the plugin refused before
 *  running it. Nothing was written when it is thrown. */
final class Failure extends Exception {
	private static final long serialVersionUID = 1L;
	final boolean cancelled;

	Failure(String line) { this(line, false); }

	Failure(String line, boolean cancelled) {
		super(line);
		this.cancelled = cancelled;
	}
}
