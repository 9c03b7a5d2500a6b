// The patch protocol (vr-workbench-patch/1), server side: framing, requests, validation, replies.
//
// Plain C# (.NET Framework 4.x, C# 7.2), no UnityEngine: the same code runs in the Unity
// package (VrPatchServer) and under mono in the workbench's tests, where it must give the
// same replies, byte for byte, as the Python reference server (instruments/patch_server.py).
// The protocol is specified in docs/vr/patch-protocol.md of the workbench:
//
//   one JSON object per line, UTF-8, "\n" (or "\r\n") terminated, at most 4096 bytes with
//   the terminator; every request carries an integer "id" and gets exactly one reply with
//   that id, in order; {"ok": false, "id": N, "error": "..."} for anything wrong (id null
//   when the line is not a JSON object with an integer id); the connection stays open.
//
//   hello  {"cmd": "hello", "id": 1, "protocol": "vr-workbench-patch/1", "client": "..."}
//   show   {"cmd": "show", "id": 2, "rgb": [r, g, b]}   optional: "window" (0, 1],
//          "surround" [r, g, b], "eye" "left" | "right" | "both"; any other field is refused
//          by name
//   target {"cmd": "target", "id": 3}                   optional: "eye"
//   bye    {"cmd": "bye", "id": 4}                      reply, then the server closes
using System;
using System.Collections.Generic;
using System.Globalization;
using System.Text;

namespace VrColourWorkbench.Patch
{
    /// <summary>Which panel shows a patch; the other one is black.</summary>
    public enum PatchEye { Both = 0, Left = 1, Right = 2 }

    /// <summary>What a presenter is asked to do: show a patch, show the centring target, or (the client has left) go back to its own picture.</summary>
    public enum PatchCommandKind { Show = 0, Target = 1, ClientLeft = 2 }

    /// <summary>One validated picture to present: a patch (full field or an APL window) or the centring target.</summary>
    public sealed class PatchCommand
    {
        public readonly PatchCommandKind Kind;
        /// <summary>DAC values 0..255 of the patch (black for the target).</summary>
        public readonly int R, G, B;
        /// <summary>Fraction of the field the patch covers, in (0, 1]; 1 is full field.</summary>
        public readonly double Window;
        /// <summary>DAC values 0..255 of the rest of the field (an APL patch's surround).</summary>
        public readonly int SurroundR, SurroundG, SurroundB;
        public readonly PatchEye Eye;

        public PatchCommand(PatchCommandKind kind, int[] rgb, double window, int[] surround, PatchEye eye)
        {
            Kind = kind;
            R = rgb[0]; G = rgb[1]; B = rgb[2];
            Window = window;
            SurroundR = surround[0]; SurroundG = surround[1]; SurroundB = surround[2];
            Eye = eye;
        }

        public static PatchCommand Show(int r, int g, int b)
        {
            return new PatchCommand(PatchCommandKind.Show, new[] { r, g, b }, 1.0, new[] { 0, 0, 0 }, PatchEye.Both);
        }

        public static PatchCommand Target(PatchEye eye)
        {
            return new PatchCommand(PatchCommandKind.Target, new[] { 0, 0, 0 }, 1.0, new[] { 0, 0, 0 }, eye);
        }

        /// <summary>The client has gone (bye, closed, dropped): the application may show its own picture again.</summary>
        public static PatchCommand ClientLeft()
        {
            return new PatchCommand(PatchCommandKind.ClientLeft, new[] { 0, 0, 0 }, 1.0, new[] { 0, 0, 0 }, PatchEye.Both);
        }

        /// <summary>A window smaller than the field (an APL patch).</summary>
        public bool IsAplPatch { get { return Window < 1.0; } }

        /// <summary>"[255, 128, 0]", "[255, 255, 255] as 0.03 of the field on [128, 128, 128]", "the centring target", + the eye.</summary>
        public string Describe()
        {
            if (Kind == PatchCommandKind.ClientLeft) return "nothing (the client has left)";
            string what = Kind == PatchCommandKind.Target
                ? "the centring target"
                : Triple(R, G, B) + (IsAplPatch
                    ? " as " + Window.ToString("R", CultureInfo.InvariantCulture) + " of the field on " + Triple(SurroundR, SurroundG, SurroundB)
                    : "");
            return Eye == PatchEye.Both ? what : what + " in the " + PatchProtocol.EyeName(Eye) + " eye (the other black)";
        }

        /// <summary>One JSON line recording what was presented (the same as the Python reference server's --record).</summary>
        public string ToRecord()
        {
            var record = new JsonObject().Add("cmd", Kind == PatchCommandKind.Show ? "show" : "target");
            if (Kind == PatchCommandKind.Show)
            {
                record.Add("rgb", new List<object> { R, G, B })
                      .Add("window", Window)
                      .Add("surround", new List<object> { SurroundR, SurroundG, SurroundB });
            }
            record.Add("eye", PatchProtocol.EyeName(Eye));
            return PatchJson.Write(record);
        }

        internal static string Triple(int r, int g, int b)
        {
            return "[" + r.ToString(CultureInfo.InvariantCulture) + ", " + g.ToString(CultureInfo.InvariantCulture)
                 + ", " + b.ToString(CultureInfo.InvariantCulture) + "]";
        }
    }

    /// <summary>What a server accepts: all of today's protocol, or a server written before an addition.</summary>
    public sealed class PatchServerOptions
    {
        /// <summary>What the hello reply names as the display (it goes into the workbench's journal).</summary>
        public string DisplayName = "Unity VrPatchServer";
        /// <summary>Accept show's "window" and "surround" (APL patches).</summary>
        public bool AplPatches = true;
        /// <summary>Accept the "eye" field of show and target.</summary>
        public bool EyeField = true;
        /// <summary>Accept the "target" command.</summary>
        public bool TargetCommand = true;
        /// <summary>A client silent this long is dropped (the workbench is silent while the CS-2000 measures: minutes).</summary>
        public double IdleTimeoutS = 600.0;
        /// <summary>Longest wait for the presenter to say a frame was presented before answering ok:false.</summary>
        public double PresentTimeoutS = 5.0;
        /// <summary>How long a new connection waits for the current client to finish before it is told the server is busy.</summary>
        public double BusyGraceS = 0.5;
    }

    /// <summary>The kinds of request line.</summary>
    public enum PatchRequestKind { Refused = 0, Hello = 1, Show = 2, Target = 3, Bye = 4 }

    /// <summary>One request line, understood: either refused (with its reply) or a valid request.</summary>
    public sealed class PatchRequest
    {
        public PatchRequestKind Kind;
        /// <summary>The request's id as sent (a JsonNumber), or null when it could not be read.</summary>
        public object Id;
        /// <summary>For show and target: what to present.</summary>
        public PatchCommand Command;
        /// <summary>For hello: the client's "client" string, if any.</summary>
        public string Client;
        /// <summary>The reply already decided (a refusal, or hello's answer); null for show/target/bye.</summary>
        public string Reply;
    }

    /// <summary>The protocol's constants, request parsing and replies (no I/O).</summary>
    public static class PatchProtocol
    {
        public const string Name = "vr-workbench-patch/1";
        /// <summary>Longest line either side may send, terminator included.</summary>
        public const int MaxLineBytes = 4096;

        static readonly UTF8Encoding StrictUtf8 = new UTF8Encoding(false, true);
        static readonly UTF8Encoding LenientUtf8 = new UTF8Encoding(false, false);

        public static string EyeName(PatchEye eye)
        {
            return eye == PatchEye.Left ? "left" : eye == PatchEye.Right ? "right" : "both";
        }

        /// <summary>Fields a show request may carry with these options, in the order error messages list them.</summary>
        public static string[] ShowFields(PatchServerOptions options)
        {
            var fields = new List<string> { "cmd", "id", "rgb" };
            if (options.AplPatches) { fields.Add("window"); fields.Add("surround"); }
            if (options.EyeField) fields.Add("eye");
            return fields.ToArray();
        }

        public static string[] TargetFields(PatchServerOptions options)
        {
            return options.EyeField ? new[] { "cmd", "id", "eye" } : new[] { "cmd", "id" };
        }

        /// <summary>Understands one request line (without its terminator).</summary>
        public static PatchRequest Parse(byte[] line, PatchServerOptions options)
        {
            object parsed;
            try
            {
                parsed = PatchJson.Parse(StrictUtf8.GetString(line));
            }
            catch (Exception error) when (error is PatchJsonException || error is ArgumentException)
            {
                return Refuse(null, "not JSON: " + LenientUtf8.GetString(line, 0, Math.Min(line.Length, 80)));
            }
            var request = parsed as JsonObject;
            if (request == null) return Refuse(null, "a request must be a JSON object");
            object id = request.Get("id");
            var idNumber = id as JsonNumber;
            if (idNumber == null || !idNumber.IsIntegerLiteral)
                return Refuse(null, "a request must carry an integer 'id'; got " + (request.Has("id") ? JsonText(id) : "none"));
            object command;
            if (!request.TryGet("cmd", out command))
                return Refuse(id, "a request must carry a 'cmd': " + CommandList(options));
            switch (command as string)
            {
                case "hello": return Hello(request, id, options);
                case "show": return Show(request, id, options);
                case "target":
                    if (options.TargetCommand) return Target(request, id, options);
                    break;
                case "bye": return new PatchRequest { Kind = PatchRequestKind.Bye, Id = id };
            }
            string name = command is string ? "'" + Clip((string)command) + "'" : JsonText(command);
            return Refuse(id, "unknown cmd " + name + "; use " + CommandList(options));
        }

        static string CommandList(PatchServerOptions options)
        {
            return options.TargetCommand ? "hello, show, target or bye" : "hello, show or bye";
        }

        static PatchRequest Hello(JsonObject request, object id, PatchServerOptions options)
        {
            if (!(request.Get("protocol") is string) || (string)request.Get("protocol") != Name)
            {
                var refusal = new JsonObject().Add("ok", false).Add("id", id).Add("protocol", Name)
                                              .Add("error", "this server speaks " + Name);
                return new PatchRequest { Kind = PatchRequestKind.Refused, Id = id, Reply = PatchJson.Write(refusal) };
            }
            var reply = new JsonObject().Add("ok", true).Add("id", id).Add("protocol", Name).Add("display", options.DisplayName);
            return new PatchRequest
            {
                Kind = PatchRequestKind.Hello, Id = id, Client = request.Get("client") as string, Reply = PatchJson.Write(reply),
            };
        }

        static string UnknownField(JsonObject request, string command, string[] known)
        {
            foreach (var member in request.Members)
            {
                if (Array.IndexOf(known, member.Key) < 0)
                    return "unknown field '" + Clip(member.Key) + "' in " + command + "; this server knows " + string.Join(", ", known);
            }
            return null;
        }

        static PatchRequest Show(JsonObject request, object id, PatchServerOptions options)
        {
            string unknown = UnknownField(request, "show", ShowFields(options));
            if (unknown != null) return Refuse(id, unknown);
            string error;
            int[] rgb = DacTriple(request.Get("rgb"), "rgb", out error);
            if (rgb == null) return Refuse(id, error);
            double window = 1.0;
            object value;
            if (request.TryGet("window", out value))
            {
                var number = value as JsonNumber;
                if (number == null || double.IsNaN(number.Value) || !(number.Value > 0.0 && number.Value <= 1.0))
                    return Refuse(id, "patch window " + JsonText(value) + " must be a number in (0, 1] (the fraction of the field)");
                window = number.Value;
            }
            int[] surround = { 0, 0, 0 };
            if (request.TryGet("surround", out value))
            {
                surround = DacTriple(value, "surround", out error);
                if (surround == null) return Refuse(id, error);
            }
            PatchEye eye;
            if (!Eye(request, out eye, out error)) return Refuse(id, error);
            return new PatchRequest
            {
                Kind = PatchRequestKind.Show, Id = id,
                Command = new PatchCommand(PatchCommandKind.Show, rgb, window, surround, eye),
            };
        }

        static PatchRequest Target(JsonObject request, object id, PatchServerOptions options)
        {
            string unknown = UnknownField(request, "target", TargetFields(options));
            if (unknown != null) return Refuse(id, unknown);
            PatchEye eye;
            string error;
            if (!Eye(request, out eye, out error)) return Refuse(id, error);
            return new PatchRequest { Kind = PatchRequestKind.Target, Id = id, Command = PatchCommand.Target(eye) };
        }

        static bool Eye(JsonObject request, out PatchEye eye, out string error)
        {
            eye = PatchEye.Both;
            error = null;
            object value;
            if (!request.TryGet("eye", out value)) return true;
            switch (value as string)
            {
                case "both": return true;
                case "left": eye = PatchEye.Left; return true;
                case "right": eye = PatchEye.Right; return true;
            }
            error = "patch eye " + JsonText(value) + " must be \"left\", \"right\" or \"both\"";
            return false;
        }

        /// <summary>Three JSON integers 0..255 (integral numbers such as 255.0 are accepted), or null with the error.</summary>
        static int[] DacTriple(object value, string field, out string error)
        {
            error = null;
            var list = value as List<object>;
            if (list == null || list.Count != 3)
            {
                error = "patch " + field + " " + JsonText(value) + " must be three DAC values [r, g, b]";
                return null;
            }
            var result = new int[3];
            for (int i = 0; i < 3; i++)
            {
                var number = list[i] as JsonNumber;
                if (number == null || double.IsNaN(number.Value) || number.Value != Math.Floor(number.Value)
                    || number.Value < 0 || number.Value > 255)
                {
                    error = "patch " + field + " " + JsonText(value) + " must be integers 0..255 (8-bit DAC values)";
                    return null;
                }
                result[i] = (int)number.Value;
            }
            return result;
        }

        /// <summary>Characters of a client's text quoted back in an error.</summary>
        public const int ClipLength = 80;

        /// <summary>A client's text cut to <see cref="ClipLength"/> characters (so a reply stays under the line limit).</summary>
        public static string Clip(string text)
        {
            return text.Length <= ClipLength ? text : text.Substring(0, ClipLength) + "...";
        }

        static string JsonText(object value) { return Clip(PatchJson.Write(value)); }

        static PatchRequest Refuse(object id, string error)
        {
            return new PatchRequest { Kind = PatchRequestKind.Refused, Id = id, Reply = ErrorReply(id, error) };
        }

        public static string OkReply(object id)
        {
            return PatchJson.Write(new JsonObject().Add("ok", true).Add("id", id));
        }

        public static string ErrorReply(object id, string error)
        {
            return PatchJson.Write(new JsonObject().Add("ok", false).Add("id", id).Add("error", error));
        }

        /// <summary>The reply to a line over <see cref="MaxLineBytes"/>; the server then skips to the line's end.</summary>
        public static string OversizedReply()
        {
            return ErrorReply(null, "line longer than " + MaxLineBytes.ToString(CultureInfo.InvariantCulture)
                                    + " bytes (the protocol's limit, terminator included); skipped to its end");
        }

        /// <summary>The one line a second connection gets before the server closes it.</summary>
        public static string BusyReply(string peer, string client)
        {
            string who = string.IsNullOrEmpty(client) ? peer : peer + " (" + Clip(client) + ")";
            return ErrorReply(null, "busy: this patch server is serving " + who
                                    + " \u2014 one client at a time; close that client first");
        }

        /// <summary>A reply line as bytes on the wire (UTF-8, "\n").</summary>
        public static byte[] Encode(string reply)
        {
            return StrictUtf8.GetBytes(reply + "\n");
        }
    }

    /// <summary>Splits a byte stream into request lines of at most <see cref="PatchProtocol.MaxLineBytes"/> bytes.</summary>
    /// <remarks>
    /// Partial lines are kept until their terminator arrives; "\r\n" is accepted. A line longer
    /// than the limit (terminator included) is reported once, as a null frame, as soon as it
    /// passes the limit; its remaining bytes are skipped up to its "\n".
    /// </remarks>
    public sealed class PatchLineFramer
    {
        readonly byte[] buffer = new byte[PatchProtocol.MaxLineBytes];
        int count;
        bool skipping;

        /// <summary>Adds received bytes; complete lines (without terminator) and null for an oversized line are appended to frames.</summary>
        public void Feed(byte[] data, int offset, int length, List<byte[]> frames)
        {
            for (int i = offset; i < offset + length; i++)
            {
                byte b = data[i];
                if (skipping)
                {
                    if (b == (byte)'\n') skipping = false;
                    continue;
                }
                if (b == (byte)'\n')
                {
                    int end = count > 0 && buffer[count - 1] == (byte)'\r' ? count - 1 : count;
                    var line = new byte[end];
                    Array.Copy(buffer, line, end);
                    frames.Add(line);
                    count = 0;
                    continue;
                }
                if (count == PatchProtocol.MaxLineBytes - 1)  // with its "\n" still to come, the line is over the limit
                {
                    frames.Add(null);
                    count = 0;
                    skipping = true;
                    continue;
                }
                buffer[count++] = b;
            }
        }

        /// <summary>Bytes of an unfinished line held.</summary>
        public int Pending { get { return count; } }
    }
}
