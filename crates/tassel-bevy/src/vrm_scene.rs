//! `.vrm` scenes through Bevy's own glTF loader: a VRM file is a GLB whose VRM extensions
//! Bevy ignores, so the loader is offered the extension and told not to refuse the
//! `extensionsRequired` entries it does not know.

use bevy::app::App;
use bevy::asset::io::Reader;
use bevy::asset::{AssetApp, AssetLoader, LoadContext};
use bevy::gltf::extensions::GltfExtensionHandlers;
use bevy::gltf::{DefaultGltfImageSampler, Gltf, GltfError, GltfLoader, GltfLoaderSettings};
use bevy::image::{CompressedImageFormatSupport, CompressedImageFormats};
use bevy::log::warn;
use bevy::reflect::TypePath;

/// Bevy's [`GltfLoader`] for the `vrm` extension.
#[derive(TypePath)]
pub struct VrmSceneLoader(pub GltfLoader);

impl AssetLoader for VrmSceneLoader {
    type Asset = Gltf;
    type Settings = GltfLoaderSettings;
    type Error = GltfError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        settings: &GltfLoaderSettings,
        load_context: &mut LoadContext<'_>,
    ) -> Result<Gltf, GltfError> {
        // A VRM lists `VRMC_vrm` in `extensionsRequired`; Bevy's loader refuses required
        // extensions it does not know unless validation is off. Bevy ignores the VRM
        // extensions (Tassel reads the springs); the glTF core is still parsed in full.
        let settings = GltfLoaderSettings {
            load_meshes: settings.load_meshes,
            load_materials: settings.load_materials,
            load_cameras: settings.load_cameras,
            load_lights: settings.load_lights,
            load_animations: settings.load_animations,
            include_source: settings.include_source,
            default_sampler: settings.default_sampler.clone(),
            override_sampler: settings.override_sampler,
            validate: false,
            convert_coordinates: settings.convert_coordinates,
            skinned_mesh_bounds_policy: settings.skinned_mesh_bounds_policy,
        };
        self.0.load(reader, &settings, load_context).await
    }

    fn extensions(&self) -> &[&str] {
        &["vrm"]
    }
}

/// Registers [`VrmSceneLoader`], built like Bevy's `GltfPlugin` builds its loader (its
/// sampler, extension handlers and compressed formats). Needs `GltfPlugin`.
pub(crate) fn register(app: &mut App) {
    let world = app.world();
    let (Some(sampler), Some(handlers)) = (
        world.get_resource::<DefaultGltfImageSampler>(),
        world.get_resource::<GltfExtensionHandlers>(),
    ) else {
        warn!("tassel: GltfPlugin is not added: .vrm scenes will not load");
        return;
    };
    let loader = GltfLoader {
        supported_compressed_formats: world
            .get_resource::<CompressedImageFormatSupport>()
            .map_or(CompressedImageFormats::NONE, |f| f.0),
        custom_vertex_attributes: Default::default(),
        default_sampler: sampler.get_internal(),
        default_convert_coordinates: Default::default(),
        extensions: handlers.0.clone(),
        default_skinned_mesh_bounds_policy: Default::default(),
    };
    app.register_asset_loader(VrmSceneLoader(loader));
}
