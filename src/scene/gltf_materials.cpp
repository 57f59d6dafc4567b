// glTF materials and textures to the scene's (gltf_materials.h).
#include "scene/gltf_materials.h"
#include "scene/gltf_images.h"
#include "scene/texture_fold.h"

extern "C" {
#include "common/common.h"
}

#include <cmath>
#include <cstring>

namespace pb_gltf {
namespace {

// KHR_materials_pbrSpecularGlossiness (archived, still in many exported
// assets): the bake needs only the diffuse albedo, diffuseFactor x
// diffuseTexture; specular and glossiness do not enter a Lambertian bake.
const tinygltf::Value *spec_gloss(const tinygltf::Material &mt)
{
    auto ext = mt.extensions.find("KHR_materials_pbrSpecularGlossiness");
    return ext != mt.extensions.end() && ext->second.IsObject() ? &ext->second : nullptr;
}

// KHR_texture_transform of a textureInfo (the extension object `t`) as
// u' = a u + b v + c, v' = d u + e v + f: offset x rotation x scale with
// u' = cos u + sin v, v' = -sin u + cos v before the offset. That is the
// direction the Khronos sample TextureTransformTest marks correct (its
// arrow points at the green marker; with the matrix of columns (cos, sin),
// (-sin, cos) that some copies of the extension's text show, it points at
// the red "applied in the opposite direction" one). texCoord: the set it
// overrides to (-1: none).
void texture_transform(const tinygltf::Value &t, std::array<double, 6> &xf, int *texcoord)
{
    double off[2] = {0, 0}, sc[2] = {1, 1}, rot = 0;
    for (int k = 0; k < 2; ++k) {
        if (t.Has("offset") && t.Get("offset").IsArray() && (int)t.Get("offset").ArrayLen() > k)
            off[k] = t.Get("offset").Get(k).GetNumberAsDouble();
        if (t.Has("scale") && t.Get("scale").IsArray() && (int)t.Get("scale").ArrayLen() > k)
            sc[k] = t.Get("scale").Get(k).GetNumberAsDouble();
    }
    if (t.Has("rotation"))
        rot = t.Get("rotation").GetNumberAsDouble();
    *texcoord = t.Has("texCoord") ? t.Get("texCoord").GetNumberAsInt() : -1;
    double c = std::cos(rot), sn = std::sin(rot);
    xf = {c * sc[0], sn * sc[1], off[0], -sn * sc[0], c * sc[1], off[1]};
}

const tinygltf::Value *transform_of(const tinygltf::ExtensionMap &ext)
{
    auto it = ext.find("KHR_texture_transform");
    return it != ext.end() && it->second.IsObject() ? &it->second : nullptr;
}

// The texture a material's base (diffuse) colour comes from: core or spec-gloss.
int base_texture_index(const tinygltf::Material &mt)
{
    const tinygltf::Value *sg = spec_gloss(mt);
    if (sg && sg->Has("diffuseTexture") && sg->Get("diffuseTexture").Has("index"))
        return sg->Get("diffuseTexture").Get("index").GetNumberAsInt();
    return mt.pbrMetallicRoughness.baseColorTexture.index;
}

// The extensions that give a texture another image than its core source, in
// the order they are tried.
const char *const image_extensions[] = {"EXT_texture_avif", "EXT_texture_webp", "KHR_texture_basisu"};

// Whether texture t has extension `name` with an integer source, in *source.
bool extension_source(const tinygltf::Texture &t, const char *name, int *source)
{
    auto ext = t.extensions.find(name);
    if (ext == t.extensions.end() || !ext->second.IsObject() || !ext->second.Has("source") ||
        !ext->second.Get("source").IsInt())
        return false;
    *source = ext->second.Get("source").GetNumberAsInt();
    return true;
}

// The image a texture reads: the source of EXT_texture_avif,
// EXT_texture_webp or KHR_texture_basisu where it names an image that
// decoded, else the core source (the extensions' fallback, or -1).
int texture_source(reader &r, size_t i)
{
    const tinygltf::Texture &t = r.m.textures[i];
    int unusable = -1;
    for (const char *name : image_extensions) {
        int s;
        if (!extension_source(t, name, &s))
            continue;
        if (decode_image(r.images, s))
            return s;
        if (t.source >= 0)
            pb_logf(&r.b->log, PB_LOG_INFO, "%s: texture %zu: its %s image %d is unusable; the fallback image %d is read",
                    r.path, i, name + 12, s, t.source);
        unusable = s;
    }
    return t.source >= 0 || unusable < 0 ? t.source : unusable; // a missing or undecoded image is warned about
}

// Material mt's KHR_materials_transmission object, or nullptr.
const tinygltf::Value *transmission_of(const tinygltf::Material &mt)
{
    auto ext = mt.extensions.find("KHR_materials_transmission");
    return ext != mt.extensions.end() && ext->second.IsObject() ? &ext->second : nullptr;
}

// Whether a textureInfo value names a texture by an integer index, in *index.
bool texture_info_index(const tinygltf::Value &info, int *index)
{
    if (!info.IsObject() || !info.Has("index") || !info.Get("index").IsInt())
        return false;
    *index = info.Get("index").GetNumberAsInt();
    return true;
}

// The image texture i reads first: the first of its extensions' sources
// (texture_source's order), else its core source.
int first_source(const tinygltf::Texture &t)
{
    int s;
    for (const char *name : image_extensions)
        if (extension_source(t, name, &s))
            return s;
    return t.source;
}

// The images read_materials will ask for, in the order it asks: each
// material's base colour and emissive textures (always read), its
// transmission texture, metallic texture and normal map where nothing rules
// them out before their factors and UVs are looked at. For prefetch_images,
// which only decodes them early.
std::vector<int> images_materials_read(const reader &r)
{
    const tinygltf::Model &m = r.m;
    std::vector<int> order;
    auto add = [&](int texture) {
        if (texture >= 0 && (size_t)texture < m.textures.size())
            order.push_back(first_source(m.textures[(size_t)texture]));
    };
    for (const tinygltf::Material &mt : m.materials) {
        bool unlit = mt.extensions.find("KHR_materials_unlit") != mt.extensions.end();
        add(base_texture_index(mt));
        add(mt.emissiveTexture.index);
        const tinygltf::Value *tr = transmission_of(mt);
        int tt;
        if (!unlit && tr && tr->Has("transmissionFactor") && tr->Get("transmissionFactor").GetNumberAsDouble() > 0 &&
            tr->Has("transmissionTexture") && texture_info_index(tr->Get("transmissionTexture"), &tt))
            add(tt);
        if (!unlit && !spec_gloss(mt) && mt.pbrMetallicRoughness.metallicFactor > 0)
            add(mt.pbrMetallicRoughness.metallicRoughnessTexture.index);
        if (!unlit && !r.no_normal_maps)
            add(mt.normalTexture.index);
    }
    return order;
}

// glTF texture i as a scene texture, its image decoded now; -1 (warned)
// where it names no image or its image does not decode.
int32_t make_texture(reader &r, size_t i)
{
    const tinygltf::Model &m = r.m;
    const tinygltf::Texture &t = m.textures[i];
    int source = texture_source(r, i);
    if (source < 0 || source >= (int)m.images.size()) {
        pb_logf(&r.b->log, PB_LOG_WARN, "%s: texture %zu refers to missing image %d; ignored", r.path, i, source);
        return -1;
    }
    if (!decode_image(r.images, source))
        return -1; // warned by decode_image
    const tinygltf::Image &img = m.images[source];
    uint32_t wrap[2] = {PB_WRAP_REPEAT, PB_WRAP_REPEAT};
    if (t.sampler >= 0 && t.sampler < (int)m.samplers.size()) {
        int w[2] = {m.samplers[t.sampler].wrapS, m.samplers[t.sampler].wrapT};
        for (int k = 0; k < 2; ++k)
            wrap[k] = w[k] == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE     ? PB_WRAP_CLAMP
                      : w[k] == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? PB_WRAP_MIRROR
                                                                      : PB_WRAP_REPEAT;
    }
    return pb_sb_add_texture(r.b, img.image.data(), (uint32_t)img.width, (uint32_t)img.height, wrap[0], wrap[1],
                             (uint32_t)r.texture_srgb[i]);
}

// The scene texture a material reads as glTF texture `gltf_texture`, made
// the first time any material asks for it: so a texture no material reads
// where the bake samples (a normal or occlusion map, a metallic texture
// under a factor of 0) is never decoded. -1: none, skipped, or failed.
int32_t texture_of(reader &r, int gltf_texture, const char *material)
{
    if (gltf_texture < 0)
        return -1;
    if (gltf_texture >= (int)r.texture_map.size()) {
        pb_logf(&r.b->log, PB_LOG_WARN, "%s: material '%s' refers to missing texture %d; ignored", r.path, material,
                gltf_texture);
        return -1;
    }
    if (!r.texture_read[(size_t)gltf_texture] && !r.skip_textures) {
        r.texture_read[(size_t)gltf_texture] = 1;
        r.texture_map[(size_t)gltf_texture] = make_texture(r, (size_t)gltf_texture);
    }
    return r.texture_map[(size_t)gltf_texture];
}


// Whether a texture with texCoord `tc` and KHR_texture_transform `tm` (or
// none) reads the UVs the material's colour texture reads (TEXCOORD_0 under
// the material's one transform xf): the condition for folding it into that
// texture. *set: the set it reads.
bool reads_material_uvs(int tc, const tinygltf::Value *tm, const std::array<double, 6> &xf, int *set)
{
    std::array<double, 6> x = {1, 0, 0, 0, 1, 0};
    if (tm) {
        int over = -1;
        texture_transform(*tm, x, &over);
        tc = over >= 0 ? over : tc;
    }
    *set = tc;
    return tc == 0 && x == xf;
}

// glTF: metallic = metallicFactor x the metallicRoughness texture's blue
// channel. The kernels read one colour texture, so a metallic texture is
// folded into it (texture_fold.h) and the material's metallic becomes 0.
// It must be read with the UVs the material's colour texture is read with
// (TEXCOORD_0 under the material's one transform); else the factor alone
// stands, with a warning.
void fold_metallic(reader &r, const tinygltf::TextureInfo &info, const std::array<double, 6> &xf, pb_material &pm)
{
    if (info.index < 0 || !(pm.metallic > 0.f))
        return; // no texture, or nothing metallic (spec-gloss and unlit set 0)
    int32_t mr = texture_of(r, info.index, pm.name);
    if (mr < 0)
        return; // not decoded (warned), or textures skipped: the factor alone
    int tc;
    if (!reads_material_uvs(info.texCoord, transform_of(info.extensions), xf, &tc)) {
        pb_logf(&r.b->log, PB_LOG_WARN,
                "%s: material '%s': its metallicRoughness texture is read with other UVs than its base colour "
                "(TEXCOORD_%d or another KHR_texture_transform); metallic is its factor alone",
                r.path, pm.name, tc);
        return;
    }
    uint32_t bits;
    memcpy(&bits, &pm.metallic, 4);
    std::array<int64_t, 3> key = {pm.base_color_texture, mr, bits};
    auto it = r.folded.find(key);
    int32_t id = it != r.folded.end() ? it->second : pb_sb_fold_metallic(r.b, pm.base_color_texture, mr, pm.metallic);
    if (id < 0)
        return; // out of host memory: the builder reports it
    r.folded[key] = id;
    pb_logf(&r.b->log, PB_LOG_DEBUG, "%s: material '%s': metallic texture folded into its colour (texture %d)",
            r.path, pm.name, id);
    pm.base_color_texture = id;
    pm.metallic = 0.f;
}

// KHR_materials_transmission without KHR_materials_volume: a thin surface
// that lets a share t of the light meeting its dielectric part straight
// through, tinted by the base colour. The material becomes alpha-blended:
// its alpha is its coverage (1 for an opaque one) and pm.transmission =
// t (1 - metallic); the kernels let a ray through with probability
// 1 - alpha (1 - transmission), tinted (docs/bake.md, "Thin glass"). A
// transmission texture's red channel scales t per texel: on an opaque
// material it goes into the colour texture's alpha (coverage is 1 there), on
// a blended one it is read as it stands (pm.transmission_texture). Not
// modelled: the surface's specular reflection, refraction.
void apply_transmission(reader &r, const tinygltf::Material &mt, const std::array<double, 6> &xf, pb_material &pm)
{
    const tinygltf::Value *ext = transmission_of(mt);
    if (!ext || !ext->Has("transmissionFactor"))
        return;
    double t = ext->Get("transmissionFactor").GetNumberAsDouble();
    t = t < 1.0 ? t : 1.0;
    double pass = t * (1.0 - pm.metallic);
    if (!(pass > 0.0))
        return; // nothing passes (no factor, NaN, or all metal): as it was
    if (pm.alpha_mode == PB_ALPHA_MASK) {
        pb_logf(&r.b->log, PB_LOG_WARN,
                "%s: material '%s': transmission on an alpha-masked material is not modelled; it stays opaque "
                "where the mask keeps it", r.path, pm.name);
        return;
    }
    // the transmission texture's red channel scales the factor, where it is
    // read with the colour texture's UVs
    const tinygltf::Value &tx = ext->Has("transmissionTexture") ? ext->Get("transmissionTexture") : tinygltf::Value();
    int ti;
    int32_t tt = texture_info_index(tx, &ti) ? texture_of(r, ti, pm.name) : -1;
    if (tt >= 0) {
        int tc = tx.Has("texCoord") && tx.Get("texCoord").IsInt() ? tx.Get("texCoord").GetNumberAsInt() : 0;
        const tinygltf::Value *tm = tx.Has("extensions") && tx.Get("extensions").Has("KHR_texture_transform")
                                        ? &tx.Get("extensions").Get("KHR_texture_transform")
                                        : nullptr;
        if (!reads_material_uvs(tc, tm, xf, &tc)) {
            pb_logf(&r.b->log, PB_LOG_WARN,
                    "%s: material '%s': its transmissionTexture is read with other UVs than its base colour "
                    "(TEXCOORD_%d or another KHR_texture_transform); its transmissionFactor stands alone",
                    r.path, pm.name, tc);
            tt = -1;
        }
    }
    if (tt >= 0 && pm.alpha_mode == PB_ALPHA_OPAQUE) {
        // coverage 1, so the colour texture's alpha is free to carry the
        // texture's scale of tau: the light through is tinted per texel
        int32_t id = pb_sb_fold_transmission_scale(r.b, pm.base_color_texture, tt);
        if (id < 0)
            return; // out of host memory: the builder reports it
        pm.base_color_texture = id;
        pm.base_color[3] = 1.f;
        pm.alpha_mode = PB_ALPHA_BLEND;
        pm.transmission = (float)pass;
        pm.transmission_in_alpha = 1;
        return;
    }
    if (tt >= 0) {
        // alpha is coverage already: the texture is read beside the colour
        // one, its red scaling tau per texel (the light through tinted as
        // without it)
        pm.transmission = (float)pass;
        pm.transmission_texture = tt;
        return;
    }
    if (pm.alpha_mode == PB_ALPHA_OPAQUE && pm.base_color_texture >= 0) {
        // glTF ignores an opaque material's alpha; blended, its texture's would count
        int32_t id = pb_sb_opaque_texture(r.b, pm.base_color_texture);
        if (id < 0)
            return; // out of host memory: the builder reports it
        pm.base_color_texture = id;
    }
    if (pm.alpha_mode == PB_ALPHA_OPAQUE)
        pm.base_color[3] = 1.f; // glTF ignores an opaque material's alpha: it covers all
    pm.alpha_mode = PB_ALPHA_BLEND;
    pm.transmission = (float)pass;
}

// Whether the normal map is the only texture material `mt` reads (pm: as
// read so far): then the material's UVs may take its transform.
bool only_normal_map(const tinygltf::Material &mt, const pb_material &pm)
{
    const tinygltf::Value *tr = transmission_of(mt);
    bool transmission_texture = tr && tr->Has("transmissionTexture");
    return pm.base_color_texture < 0 && pm.emissive_texture < 0 &&
           mt.pbrMetallicRoughness.metallicRoughnessTexture.index < 0 && !transmission_texture &&
           mt.normalTexture.index >= 0;
}

// glTF normalTexture: tangent-space normals that bend the shading normal
// (docs/scene.md, "Normal maps"). The scene keeps one set of texture
// coordinates per triangle, so the map must be read with the UVs the
// material's colour texture is read with (TEXCOORD_0 under the material's one
// transform); else it is not applied, with a warning (the frame where a
// primitive has no TANGENT comes from those UVs too). Its scale must be
// finite.
void read_normal_map(reader &r, const tinygltf::NormalTextureInfo &info, const std::array<double, 6> &xf,
                     pb_material &pm)
{
    if (info.index < 0)
        return;
    int tc;
    if (!reads_material_uvs(info.texCoord, transform_of(info.extensions), xf, &tc)) {
        pb_logf(&r.b->log, PB_LOG_WARN,
                "%s: material '%s': its normalTexture is read with other UVs than its base colour "
                "(TEXCOORD_%d or another KHR_texture_transform); not applied", r.path, pm.name, tc);
        return;
    }
    if (!std::isfinite(info.scale) || std::fabs(info.scale) > 1e6) {
        pb_logf(&r.b->log, PB_LOG_WARN, "%s: material '%s': normalTexture scale %g is not usable; not applied",
                r.path, pm.name, info.scale);
        return;
    }
    int32_t t = texture_of(r, info.index, pm.name);
    if (t < 0)
        return; // not decoded (warned), or textures skipped
    pm.normal_texture = t;
    pm.normal_scale = (float)info.scale;
}

} // namespace

pb_result read_textures(reader &r, int skip)
{
    const tinygltf::Model &m = r.m;
    r.texture_map.assign(m.textures.size(), -1);
    r.texture_read.assign(m.textures.size(), 0);
    r.skip_textures = skip != 0;
    if (skip)
        return PB_OK;
    // colour textures are sRGB: note which ones the materials use that way
    r.texture_srgb.assign(m.textures.size(), 0);
    for (const tinygltf::Material &mt : m.materials) {
        int t0 = base_texture_index(mt), t1 = mt.emissiveTexture.index;
        if (t0 >= 0 && t0 < (int)m.textures.size()) r.texture_srgb[t0] = 1;
        if (t1 >= 0 && t1 < (int)m.textures.size()) r.texture_srgb[t1] = 1;
    }
    r.b->stats.textures_in = (uint32_t)m.textures.size();
    return PB_OK;
}

void read_materials(reader &r)
{
    if (!r.skip_textures)
        prefetch_images(r.images, images_materials_read(r));
    for (const tinygltf::Material &mt : r.m.materials) {
        pb_material pm = pb_material_default();
        snprintf(pm.name, sizeof pm.name, "%s", mt.name.c_str());
        const tinygltf::PbrMetallicRoughness &pbr = mt.pbrMetallicRoughness;
        for (int k = 0; k < 4 && k < (int)pbr.baseColorFactor.size(); ++k)
            pm.base_color[k] = (float)pbr.baseColorFactor[k];
        pm.metallic = (float)pbr.metallicFactor;
        pm.roughness = (float)pbr.roughnessFactor;
        double strength = 1.0;
        auto ext = mt.extensions.find("KHR_materials_emissive_strength");
        if (ext != mt.extensions.end() && ext->second.Has("emissiveStrength"))
            strength = ext->second.Get("emissiveStrength").GetNumberAsDouble();
        for (int k = 0; k < 3 && k < (int)mt.emissiveFactor.size(); ++k)
            pm.emissive[k] = (float)(mt.emissiveFactor[k] * strength);
        pm.alpha_mode = mt.alphaMode == "MASK" ? PB_ALPHA_MASK : mt.alphaMode == "BLEND" ? PB_ALPHA_BLEND : PB_ALPHA_OPAQUE;
        pm.alpha_cutoff = (float)mt.alphaCutoff;
        pm.double_sided = mt.doubleSided ? 1u : 0u;
        pm.base_color_texture = texture_of(r, base_texture_index(mt), pm.name);
        pm.emissive_texture = texture_of(r, mt.emissiveTexture.index, pm.name);
        if (const tinygltf::Value *sg = spec_gloss(mt)) {
            pm.metallic = 0.f; /* the diffuse colour is the albedo as it stands */
            for (int k = 0; k < 4; ++k)
                pm.base_color[k] = 1.f;
            if (sg->Has("diffuseFactor") && sg->Get("diffuseFactor").IsArray())
                for (int k = 0; k < 4 && k < (int)sg->Get("diffuseFactor").ArrayLen(); ++k)
                    pm.base_color[k] = (float)sg->Get("diffuseFactor").Get(k).GetNumberAsDouble();
        }
        /* KHR_materials_unlit: the surface shows its base colour whatever
         * lights it, so to the probes it is a source of that radiance, not a
         * reflector: it emits base colour x base texture and reflects nothing */
        if (mt.extensions.find("KHR_materials_unlit") != mt.extensions.end()) {
            for (int k = 0; k < 3; ++k)
                pm.emissive[k] = pm.base_color[k], pm.base_color[k] = 0.f;
            pm.emissive_texture = pm.base_color_texture;
            pm.metallic = 0.f;
        }
        /* KHR_texture_transform: the scene keeps one UV set per triangle, so a
         * material's UVs take its base colour texture's transform (else its
         * emissive texture's, else its normal map's); a different one on the
         * other is warned of */
        std::array<double, 6> xf = {1, 0, 0, 0, 1, 0}, xe = xf;
        int tc_base = -1, tc_em = -1;
        const tinygltf::Value *tb = nullptr;
        if (const tinygltf::Value *sg = spec_gloss(mt)) {
            if (sg->Has("diffuseTexture") && sg->Get("diffuseTexture").Has("extensions") &&
                sg->Get("diffuseTexture").Get("extensions").Has("KHR_texture_transform"))
                tb = &sg->Get("diffuseTexture").Get("extensions").Get("KHR_texture_transform");
        } else {
            tb = transform_of(pbr.baseColorTexture.extensions);
        }
        const tinygltf::Value *te = transform_of(mt.emissiveTexture.extensions);
        if (tb)
            texture_transform(*tb, xf, &tc_base);
        if (te)
            texture_transform(*te, xe, &tc_em);
        const tinygltf::Value *tn = transform_of(mt.normalTexture.extensions);
        if (!tb && te && pm.base_color_texture < 0)
            xf = xe, tc_base = tc_em;
        else if (tn && !r.no_normal_maps && only_normal_map(mt, pm)) // its UVs are the only ones read
            texture_transform(*tn, xf, &tc_base);
        else if (te && pm.emissive_texture >= 0 && pm.base_color_texture >= 0 && xe != xf)
            pb_logf(&r.b->log, PB_LOG_WARN,
                    "%s: material '%s': its emissive texture's KHR_texture_transform differs from its base colour "
                    "texture's; the base colour's is applied to both", r.path, pm.name);
        if (tc_base > 0)
            pb_logf(&r.b->log, PB_LOG_WARN, "%s: material '%s': KHR_texture_transform selects TEXCOORD_%d; "
                    "only TEXCOORD_0 is read", r.path, pm.name, tc_base);
        if (mt.extensions.find("KHR_materials_unlit") == mt.extensions.end())
            apply_transmission(r, mt, xf, pm);
        fold_metallic(r, pbr.metallicRoughnessTexture, xf, pm);
        // an unlit surface reflects nothing: no normal bends it
        if (!r.no_normal_maps && mt.extensions.find("KHR_materials_unlit") == mt.extensions.end())
            read_normal_map(r, mt.normalTexture, xf, pm);
        r.uv_transform.push_back(xf);
        pb_sb_add_material(r.b, &pm);
    }
    r.uv_transform.push_back({1, 0, 0, 0, 1, 0});
    pb_material def = pb_material_default();
    snprintf(def.name, sizeof def.name, "default");
    r.default_material = (uint32_t)pb_sb_add_material(r.b, &def);
    for (size_t i = 0; !r.skip_textures && i < r.texture_read.size(); ++i)
        r.b->stats.textures_unread += r.texture_read[i] == 0;
}

} // namespace pb_gltf
