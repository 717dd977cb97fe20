// Carve.cs: organtex's C API from C# through P/Invoke, as a Unity project
// calls a native plug-in (Assets/Plugins/liborgantex.so, [DllImport]).
//
//   mcs -out:Carve.exe capi/examples/Carve.cs
//   LD_LIBRARY_PATH=PREFIX/lib mono Carve.exe BAKE_DIR
//
// Opens the default bake, carves ten steps of the tunnel through the
// uterine wall, reads each step's new faces (ids, vertices, atlas uvs,
// corner colours) and a page's texels, checks a bad tet id is refused with
// its message while the session goes on. Exit status 0 when all holds.
using System;
using System.Runtime.InteropServices;

static class Organtex
{
    const string Lib = "organtex";

    public enum Status { Ok = 0, NullArgument = 1, InvalidArgument = 2, NotFound = 3, Io = 4, Format = 5, Panic = 6 }

    [StructLayout(LayoutKind.Sequential)]
    public struct CarvingOptions
    {
        public double TexelsPerUnit;
        public uint PageSize;
        [MarshalAs(UnmanagedType.I1)] public bool BackgroundTexels;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct TetMesh
    {
        public IntPtr Positions;
        public UIntPtr VertexCount;
        public IntPtr Tets;
        public UIntPtr TetCount;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct Face
    {
        public uint Id;
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = 3)] public uint[] Vertices;
        public uint Page;
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = 6)] public float[] Uvs;
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = 9)] public byte[] Colours;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct Step
    {
        public IntPtr Removed; public UIntPtr RemovedCount;
        public IntPtr Appeared; public UIntPtr AppearedCount;
        public IntPtr Vanished; public UIntPtr VanishedCount;
        public IntPtr Dirty; public UIntPtr DirtyCount;
        public IntPtr Released; public UIntPtr ReleasedCount;
        [MarshalAs(UnmanagedType.I1)] public bool TexelsPending;
        public double Seconds;
    }

    [DllImport(Lib)] public static extern IntPtr organtex_version();
    [DllImport(Lib)] public static extern uint organtex_abi_version();
    [DllImport(Lib)] public static extern IntPtr organtex_last_error();
    [DllImport(Lib)] public static extern Status organtex_bake_open(string dir, out IntPtr bake);
    [DllImport(Lib)] public static extern void organtex_bake_free(IntPtr bake);
    [DllImport(Lib)] public static extern Status organtex_bake_node(IntPtr bake, string name, out IntPtr node);
    [DllImport(Lib)] public static extern void organtex_node_free(IntPtr node);
    [DllImport(Lib)] public static extern Status organtex_node_tet_mesh(IntPtr node, out TetMesh mesh);
    [DllImport(Lib)] public static extern CarvingOptions organtex_carving_options_default();
    [DllImport(Lib)] public static extern Status organtex_carving_new(IntPtr node, ref CarvingOptions options, out IntPtr carving);
    [DllImport(Lib)] public static extern void organtex_carving_free(IntPtr carving);
    [DllImport(Lib)] public static extern Status organtex_carving_capsule(IntPtr carving, double[] a, double[] b, double radius, out Step step);
    [DllImport(Lib)] public static extern Status organtex_carving_remove(IntPtr carving, uint[] ids, UIntPtr count, out Step step);
    [DllImport(Lib)] public static extern Status organtex_carving_page(IntPtr carving, uint page, out IntPtr rgba, out uint side);

    public static string LastError() { return Marshal.PtrToStringAnsi(organtex_last_error()); }

    public static void Must(Status s, string what)
    {
        if (s != Status.Ok) throw new Exception(what + ": " + s + ": " + LastError());
    }
}

static class Carve
{
    static double[] WallPath(int step)
    {
        double a = step / 100.0 * 0.95 * 2.0 * Math.PI;
        return new double[] { 18.5 * Math.Cos(a), 11.8 * Math.Sin(a), 20.0 };
    }

    static int Main(string[] args)
    {
        if (args.Length != 1) { Console.Error.WriteLine("usage: mono Carve.exe BAKE_DIR"); return 2; }
        int failures = 0;
        Action<bool, string> check = (ok, what) => { if (!ok) { Console.Error.WriteLine("Carve: check failed: " + what); failures++; } };
        try
        {
            check(Organtex.organtex_abi_version() == 1, "ABI 1");
            check(Marshal.SizeOf(typeof(Organtex.Face)) == 56, "organtex_face is 56 bytes");
            check(Marshal.SizeOf(typeof(Organtex.Step)) == 96, "organtex_step is 96 bytes");
            IntPtr bake, node, carving;
            Organtex.Must(Organtex.organtex_bake_open(args[0], out bake), "organtex_bake_open");
            Organtex.Must(Organtex.organtex_bake_node(bake, "uterus", out node), "organtex_bake_node");
            Organtex.TetMesh mesh;
            Organtex.Must(Organtex.organtex_node_tet_mesh(node, out mesh), "organtex_node_tet_mesh");
            var options = Organtex.organtex_carving_options_default();
            check(options.TexelsPerUnit == 8.0 && options.PageSize == 1024, "default options");
            Organtex.Must(Organtex.organtex_carving_new(node, ref options, out carving), "organtex_carving_new");
            Console.WriteLine("organtex " + Marshal.PtrToStringAnsi(Organtex.organtex_version()) + " from C#: "
                              + mesh.TetCount + " tets");

            int faces = 0, removed = 0;
            for (int i = 1; i <= 10; i++)
            {
                Organtex.Step step;
                Organtex.Must(Organtex.organtex_carving_capsule(carving, WallPath(i - 1), WallPath(i), 1.5, out step), "capsule");
                removed += (int)step.RemovedCount;
                int size = Marshal.SizeOf(typeof(Organtex.Face));
                for (int k = 0; k < (int)step.AppearedCount; k++)
                {
                    var f = (Organtex.Face)Marshal.PtrToStructure(new IntPtr(step.Appeared.ToInt64() + k * size), typeof(Organtex.Face));
                    faces++;
                    check(f.Id / 4 < (uint)mesh.TetCount, "a face's tet is in the mesh");
                    foreach (uint v in f.Vertices) check(v < (uint)mesh.VertexCount, "a face's vertex is in the mesh");
                    foreach (float uv in f.Uvs) check(uv >= 0f && uv <= 1f, "uvs lie in the page");
                    IntPtr rgba; uint side;
                    Organtex.Must(Organtex.organtex_carving_page(carving, f.Page, out rgba, out side), "organtex_carving_page");
                    int x = (int)((f.Uvs[0] + f.Uvs[2] + f.Uvs[4]) / 3f * side);
                    int y = (int)((f.Uvs[1] + f.Uvs[3] + f.Uvs[5]) / 3f * side);
                    byte alpha = Marshal.ReadByte(rgba, 4 * (y * (int)side + x) + 3);
                    check(alpha == 255, "the face's centroid texel is filled");
                }
                Console.WriteLine("step " + i + ": " + step.RemovedCount + " tets removed, " + step.AppearedCount
                                  + " faces appeared, " + step.VanishedCount + " vanished, "
                                  + (step.Seconds * 1e3).ToString("F2") + " ms");
            }
            check(removed > 100 && faces > 100, "ten steps carve");

            Organtex.Step refused;
            var past = new uint[] { (uint)mesh.TetCount };
            var status = Organtex.organtex_carving_remove(carving, past, new UIntPtr(1), out refused);
            check(status == Organtex.Status.InvalidArgument, "a tet id past the mesh is refused");
            Console.WriteLine("refused: " + Organtex.LastError());
            check(Organtex.LastError().Contains("out of range"), "the message says why");
            Organtex.Step after;
            Organtex.Must(Organtex.organtex_carving_capsule(carving, WallPath(10), WallPath(11), 1.5, out after), "a step after");

            Organtex.organtex_carving_free(carving);
            Organtex.organtex_node_free(node);
            Organtex.organtex_bake_free(bake);
        }
        catch (Exception e)
        {
            Console.Error.WriteLine("Carve: " + e.Message);
            return 1;
        }
        if (failures > 0) return 1;
        Console.WriteLine("every check holds");
        return 0;
    }
}
