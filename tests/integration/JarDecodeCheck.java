// Decodes every message of an LCM log with the generated Java types, as lcm-spy does
// (fingerprint -> class from the types jar), and prints per channel how many decoded and
// how many did not, as JSON. Used by tests/integration/test_monitoring.py.
import java.io.File;
import java.lang.reflect.Constructor;
import java.util.Enumeration;
import java.util.HashMap;
import java.util.Map;
import java.util.TreeMap;
import java.util.jar.JarEntry;
import java.util.jar.JarFile;

public class JarDecodeCheck {
  public static void main(String[] args) throws Exception {
    Map<Long, Class<?>> byFingerprint = new HashMap<>();
    try (JarFile jar = new JarFile(args[0])) {
      for (Enumeration<JarEntry> e = jar.entries(); e.hasMoreElements();) {
        String name = e.nextElement().getName();
        if (!name.endsWith(".class")) continue;
        Class<?> c = Class.forName(name.replace('/', '.').replace(".class", ""));
        try {
          byFingerprint.put(c.getField("LCM_FINGERPRINT").getLong(null), c);
        } catch (NoSuchFieldException ignored) {
        }
      }
    }
    Map<String, int[]> counts = new TreeMap<>();
    lcm.logging.Log log = new lcm.logging.Log(args[1], "r");
    while (true) {
      lcm.logging.Log.Event ev;
      try {
        ev = log.readNext();
      } catch (java.io.EOFException eof) {
        break;
      }
      if (ev.channel.equals("LCM_SELF_TEST")) continue;  // LCM's own, not a skillbus message
      int[] c = counts.computeIfAbsent(ev.channel, k -> new int[2]);
      long fp = new java.io.DataInputStream(new java.io.ByteArrayInputStream(ev.data)).readLong();
      Class<?> cls = byFingerprint.get(fp);
      try {
        Constructor<?> k = cls.getConstructor(byte[].class);
        k.newInstance((Object) ev.data);
        c[0]++;
      } catch (Exception ex) {
        c[1]++;
      }
    }
    StringBuilder out = new StringBuilder("{\"types\": " + byFingerprint.size() + ", \"channels\": {");
    boolean first = true;
    for (Map.Entry<String, int[]> e : counts.entrySet()) {
      out.append(first ? "" : ", ").append("\"").append(e.getKey()).append("\": [").append(e.getValue()[0])
          .append(", ").append(e.getValue()[1]).append("]");
      first = false;
    }
    System.out.println(out.append("}}"));
  }
}
