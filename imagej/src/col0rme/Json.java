package col0rme;

import java.util.ArrayList;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

/** A small JSON reader for what col0rme prints (--help-json, sim.json):
 *  objects as Map, arrays as List, numbers as Double. */
final class Json {
	private final String s;
	private int i;

	private Json(String s) { this.s = s; }

	static Object parse(String text) {
		Json j = new Json(text);
		Object v = j.value();
		j.space();
		if (j.i != j.s.length())
			throw j.bad("trailing text");
		return v;
	}

	private IllegalArgumentException bad(String why) {
		return new IllegalArgumentException("JSON: " + why + " at character " + i);
	}

	private void space() {
		while (i < s.length() && Character.isWhitespace(s.charAt(i)))
			i++;
	}

	private Object value() {
		space();
		if (i >= s.length())
			throw bad("unexpected end");
		char c = s.charAt(i);
		if (c == '{') return object();
		if (c == '[') return array();
		if (c == '"') return string();
		if (s.startsWith("null", i)) { i += 4; return null; }
		if (s.startsWith("true", i)) { i += 4; return Boolean.TRUE; }
		if (s.startsWith("false", i)) { i += 5; return Boolean.FALSE; }
		int b = i;
		while (i < s.length() && "+-0123456789.eE".indexOf(s.charAt(i)) >= 0)
			i++;
		if (b == i)
			throw bad("unexpected '" + c + "'");
		return Double.valueOf(s.substring(b, i));
	}

	private Map<String, Object> object() {
		Map<String, Object> m = new LinkedHashMap<String, Object>();
		i++;
		space();
		if (s.charAt(i) == '}') { i++; return m; }
		for (;;) {
			space();
			String k = string();
			space();
			if (s.charAt(i++) != ':')
				throw bad("expected ':'");
			m.put(k, value());
			space();
			char c = s.charAt(i++);
			if (c == '}') return m;
			if (c != ',') throw bad("expected ',' or '}'");
		}
	}

	private List<Object> array() {
		List<Object> a = new ArrayList<Object>();
		i++;
		space();
		if (s.charAt(i) == ']') { i++; return a; }
		for (;;) {
			a.add(value());
			space();
			char c = s.charAt(i++);
			if (c == ']') return a;
			if (c != ',') throw bad("expected ',' or ']'");
		}
	}

	private String string() {
		if (s.charAt(i) != '"')
			throw bad("expected a string");
		StringBuilder b = new StringBuilder();
		for (i++; ; i++) {
			char c = s.charAt(i);
			if (c == '"') { i++; return b.toString(); }
			if (c != '\\') { b.append(c); continue; }
			c = s.charAt(++i);
			switch (c) {
			case 'n': b.append('\n'); break;
			case 't': b.append('\t'); break;
			case 'r': b.append('\r'); break;
			case 'b': b.append('\b'); break;
			case 'f': b.append('\f'); break;
			case 'u': b.append((char) Integer.parseInt(s.substring(i + 1, i + 5), 16)); i += 4; break;
			default: b.append(c);
			}
		}
	}
}
