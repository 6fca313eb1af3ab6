//! GPU skinning and vertex morphing: compute passes that write skinned positions and normals
//! into a storage buffer that the draw pass then binds as its vertex buffer.
//!
//! Vertex data is uploaded once per mesh ([`GpuSkinner::create_skin`]); per frame only the
//! joint data is written ([`GpuSkinner::write_joints`], [`JOINT_FRAME_BYTES`] per joint). The
//! WGSL is `shaders/skin.wgsl` (one entry point per deformer) and `shaders/morph.wgsl`.

use bytemuck::{Pod, Zeroable};
use glam::{Mat3, Mat4, Quat, Vec3};
use keyrig_core::DeformerKind;
use keyrig_skin::{JointPalette, MeshBindings, SkinnedMesh};

use crate::RenderError;

/// Threads per workgroup of every compute entry point (`@workgroup_size(64)`).
pub const WORKGROUP_SIZE: u32 = 64;

/// Bytes of one rest vertex on the GPU ([`GpuSkinVertex`]).
pub const SKIN_VERTEX_BYTES: u64 = std::mem::size_of::<GpuSkinVertex>() as u64;
/// Bytes of one joint's per-frame data on the GPU ([`GpuJointFrame`]).
pub const JOINT_FRAME_BYTES: u64 = std::mem::size_of::<GpuJointFrame>() as u64;
/// Bytes of one skinned output vertex ([`SkinnedVertex`]).
pub const SKINNED_VERTEX_BYTES: u64 = std::mem::size_of::<SkinnedVertex>() as u64;

/// One rest vertex as the compute shader reads it (`SkinVertex` in skin.wgsl, 80 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuSkinVertex {
    pub position: [f32; 4],
    pub normal: [f32; 4],
    /// Up to four influencing joints (linear blend, dual quaternion).
    pub joints: [u32; 4],
    /// Their weights; unused slots have weight 0.
    pub weights: [f32; 4],
    /// The single joint of the rigid deformer.
    pub rigid_joint: u32,
    /// Bones blending: the child joint k at which the vertex blends.
    pub blend_joint: u32,
    /// Bones blending: how much of T(k) the vertex follows, 0..=1.
    pub blend_t: f32,
    pub _pad: u32,
}

/// One joint's data for one frame (`JointFrame` in skin.wgsl, 240 bytes). Column-major
/// matrices, quaternions as (x, y, z, w).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuJointFrame {
    /// M(j) = F(j)·A(j)⁻¹.
    pub model_from_bind: [[f32; 4]; 4],
    /// M(j) as a unit dual quaternion: real part.
    pub dq_real: [f32; 4],
    /// M(j) as a unit dual quaternion: dual part.
    pub dq_dual: [f32; 4],
    /// F(p(k))·R(k): the parent's animated frame times the joint's rest transform.
    pub blend_base: [[f32; 4]; 4],
    /// T(k), the joint's animated local rotation.
    pub blend_rotation: [f32; 4],
    /// Normal matrix of M(j): the inverse-transpose of its 3×3 part (M's own 3×3 when M is a
    /// rotation times a uniform scale), in the upper 3×3 of a 4×4.
    pub normal_from_bind: [[f32; 4]; 4],
}

/// One skinned (or morphed) vertex, what the draw pass reads (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SkinnedVertex {
    /// xyz and 1.
    pub position: [f32; 4],
    /// Unit normal and 0.
    pub normal: [f32; 4],
}

impl SkinnedVertex {
    #[must_use]
    pub fn new(position: Vec3, normal: Vec3) -> Self {
        SkinnedVertex { position: position.extend(1.0).to_array(), normal: normal.extend(0.0).to_array() }
    }

    #[must_use]
    pub fn position(&self) -> Vec3 {
        Vec3::new(self.position[0], self.position[1], self.position[2])
    }

    #[must_use]
    pub fn normal(&self) -> Vec3 {
        Vec3::new(self.normal[0], self.normal[1], self.normal[2])
    }
}

/// Bones-blending binding of one vertex: the child joint k and the blend parameter t
/// (docs/design.md §5.3; the parent bone j is k's parent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendBinding {
    pub joint: u32,
    pub t: f32,
}

/// The rest data of a skinned mesh, borrowed, as uploaded once to the GPU.
#[derive(Clone, Copy, Debug)]
pub struct SkinMeshInput<'a> {
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    /// Four joints per vertex for linear blend and dual quaternion.
    pub joints: &'a [[u32; 4]],
    /// Four weights per vertex (non-negative, not all zero; they are used as given).
    pub weights: &'a [[f32; 4]],
    /// The single joint per vertex of the rigid deformer.
    pub rigid_joints: &'a [u32],
    /// Bones-blending (k, t) per vertex.
    pub blend: &'a [BlendBinding],
    /// A(k)⁻¹ per joint: bind space from model space.
    pub bind_from_model: &'a [Mat4],
}

impl SkinMeshInput<'_> {
    /// Checks lengths, finiteness, joint ranges and weights.
    ///
    /// # Errors
    /// The first problem found, with the vertex or joint index.
    pub fn validate(&self) -> Result<(), RenderError> {
        let n = self.positions.len();
        let joint_count = self.bind_from_model.len();
        if n == 0 {
            return Err(RenderError::BadCount("a skinned mesh needs at least one vertex".into()));
        }
        if joint_count == 0 {
            return Err(RenderError::BadCount("a skinned mesh needs at least one joint".into()));
        }
        check_dispatch(n)?;
        let lengths = [
            ("normals", self.normals.len()),
            ("joints", self.joints.len()),
            ("weights", self.weights.len()),
            ("rigid_joints", self.rigid_joints.len()),
            ("blend", self.blend.len()),
        ];
        for (field, actual) in lengths {
            if actual != n {
                return Err(RenderError::LengthMismatch { field, expected: n, actual });
            }
        }
        for (index, m) in self.bind_from_model.iter().enumerate() {
            if !m.is_finite() {
                return Err(RenderError::NonFinite { what: "bind_from_model", index });
            }
        }
        let in_range = |vertex: usize, joint: u32| {
            if (joint as usize) < joint_count {
                Ok(())
            } else {
                Err(RenderError::JointOutOfRange { vertex, joint, joint_count })
            }
        };
        for i in 0..n {
            if !self.positions[i].is_finite() {
                return Err(RenderError::NonFinite { what: "positions", index: i });
            }
            if !self.normals[i].is_finite() {
                return Err(RenderError::NonFinite { what: "normals", index: i });
            }
            let w = self.weights[i];
            if w.iter().any(|x| !x.is_finite() || *x < 0.0) || w.iter().all(|x| *x == 0.0) {
                return Err(RenderError::BadWeights { vertex: i, weights: w });
            }
            for (slot, &joint) in self.joints[i].iter().enumerate() {
                if w[slot] != 0.0 {
                    in_range(i, joint)?;
                }
            }
            in_range(i, self.rigid_joints[i])?;
            in_range(i, self.blend[i].joint)?;
            let t = self.blend[i].t;
            if !t.is_finite() {
                return Err(RenderError::NonFinite { what: "blend.t", index: i });
            }
        }
        Ok(())
    }

    /// The GPU layout of the rest vertices.
    #[must_use]
    pub fn gpu_vertices(&self) -> Vec<GpuSkinVertex> {
        (0..self.positions.len())
            .map(|i| {
                let w = self.weights[i];
                // Slots with zero weight may hold any index; point them at joint 0.
                let mut joints = self.joints[i];
                for (slot, joint) in joints.iter_mut().enumerate() {
                    if w[slot] == 0.0 {
                        *joint = 0;
                    }
                }
                GpuSkinVertex {
                    position: self.positions[i].extend(1.0).to_array(),
                    normal: self.normals[i].extend(0.0).to_array(),
                    joints,
                    weights: w,
                    rigid_joint: self.rigid_joints[i],
                    blend_joint: self.blend[i].joint,
                    blend_t: self.blend[i].t.clamp(0.0, 1.0),
                    _pad: 0,
                }
            })
            .collect()
    }
}

fn check_dispatch(vertex_count: usize) -> Result<(), RenderError> {
    let max = 65_535usize * WORKGROUP_SIZE as usize;
    if vertex_count > max {
        return Err(RenderError::BadCount(format!(
            "{vertex_count} vertices is more than one compute dispatch covers ({max})"
        )));
    }
    Ok(())
}

/// One joint's pose for a frame, in the terms of docs/design.md §4.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointPose {
    /// M(j) = F(j)·A(j)⁻¹, the skinning matrix.
    pub model_from_bind: Mat4,
    /// M(j) as a unit dual quaternion (real part).
    pub dq_real: Quat,
    /// M(j) as a unit dual quaternion (dual part).
    pub dq_dual: Quat,
    /// F(p(j))·R(j) (identity parent for the root): where bones blending applies the partial
    /// rotation slerp(I, T(j), t).
    pub blend_base: Mat4,
    /// T(j), the animated local rotation.
    pub local_rotation: Quat,
    /// Maps bind-space normals for the rigid and linear-blend deformers (inverse-transpose of
    /// M(j)'s 3×3; normals are renormalized after blending).
    pub normal_from_bind: Mat3,
}

impl JointPose {
    /// A pose whose dual quaternion is built from M(j)'s rotation and translation (M is
    /// assumed rigid, as every keyrig skeleton's palette is).
    #[must_use]
    pub fn from_rigid(model_from_bind: Mat4, blend_base: Mat4, local_rotation: Quat) -> Self {
        let (dq_real, dual) = dual_quaternion_from_rigid(&model_from_bind);
        JointPose {
            model_from_bind,
            dq_real,
            dq_dual: Quat::from_array(dual),
            blend_base,
            local_rotation,
            normal_from_bind: Mat3::from_mat4(model_from_bind),
        }
    }

    /// The GPU layout.
    #[must_use]
    pub fn to_gpu(&self) -> GpuJointFrame {
        GpuJointFrame {
            model_from_bind: self.model_from_bind.to_cols_array_2d(),
            dq_real: self.dq_real.to_array(),
            dq_dual: self.dq_dual.to_array(),
            blend_base: self.blend_base.to_cols_array_2d(),
            blend_rotation: self.local_rotation.to_array(),
            normal_from_bind: Mat4::from_mat3(self.normal_from_bind).to_cols_array_2d(),
        }
    }
}

/// The per-frame joint data of a keyrig-skin palette: M(j), its dual quaternion (keyrig-skin's
/// own, so CPU and GPU blend identical numbers), P(k) = F(p(k))·R(k) and T(k).
#[must_use]
pub fn joint_poses(palette: &JointPalette) -> Vec<JointPose> {
    let dqs = palette.dual_quaternions().ok();
    palette
        .skinning
        .iter()
        .zip(&palette.bones_blending)
        .enumerate()
        .map(|(j, (m, bb))| {
            let model_from_bind = Mat4::from(*m);
            let blend_base = Mat4::from(bb.posed_from_joint_rest);
            let mut pose = match &dqs {
                Some(dqs) => JointPose {
                    model_from_bind,
                    dq_real: dqs[j].real,
                    dq_dual: dqs[j].dual,
                    blend_base,
                    local_rotation: bb.rotation,
                    normal_from_bind: Mat3::from_mat4(model_from_bind),
                },
                None => JointPose::from_rigid(model_from_bind, blend_base, bb.rotation),
            };
            if let Some(normals) = &palette.normal_skinning {
                pose.normal_from_bind = Mat3::from(normals[j]);
            }
            pose
        })
        .collect()
}

/// Owned GPU-ready rest data of a keyrig-skin mesh; [`OwnedSkinInput::as_input`] borrows it.
#[derive(Clone, Debug, PartialEq)]
pub struct OwnedSkinInput {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub joints: Vec<[u32; 4]>,
    pub weights: Vec<[f32; 4]>,
    pub rigid_joints: Vec<u32>,
    pub blend: Vec<BlendBinding>,
    pub bind_from_model: Vec<Mat4>,
}

impl OwnedSkinInput {
    /// Converts a keyrig-skin mesh and its bindings (from [`SkinnedMesh::bindings`]).
    #[must_use]
    pub fn from_skinned_mesh(mesh: &SkinnedMesh, bindings: &MeshBindings) -> Self {
        OwnedSkinInput {
            positions: mesh.positions.clone(),
            normals: mesh.normals.clone(),
            joints: mesh.influences.joints().iter().map(|js| js.map(u32::from)).collect(),
            weights: mesh.influences.weights().to_vec(),
            rigid_joints: bindings.rigid.iter().map(|&j| u32::from(j)).collect(),
            blend: bindings.bones_blending.iter().map(|b| BlendBinding { joint: b.joint, t: b.t }).collect(),
            bind_from_model: mesh.skeleton.joint_from_bind_model().iter().map(|a| Mat4::from(*a)).collect(),
        }
    }

    #[must_use]
    pub fn as_input(&self) -> SkinMeshInput<'_> {
        SkinMeshInput {
            positions: &self.positions,
            normals: &self.normals,
            joints: &self.joints,
            weights: &self.weights,
            rigid_joints: &self.rigid_joints,
            blend: &self.blend,
            bind_from_model: &self.bind_from_model,
        }
    }
}

/// The unit dual quaternion (real q, dual ½·(t, 0)·q) of a rigid transform.
#[must_use]
pub fn dual_quaternion_from_rigid(m: &Mat4) -> (Quat, [f32; 4]) {
    let (_, rotation, translation) = m.to_scale_rotation_translation();
    let q = rotation.normalize();
    let dual = Quat::from_xyzw(translation.x, translation.y, translation.z, 0.0) * q * 0.5;
    (q, dual.to_array())
}

/// The compute pipelines, shared by every skinned and morphed mesh.
pub struct GpuSkinner {
    skin_layout: wgpu::BindGroupLayout,
    rigid: wgpu::ComputePipeline,
    linear: wgpu::ComputePipeline,
    bones_blending: wgpu::ComputePipeline,
    dual_quaternion: wgpu::ComputePipeline,
    morph_layout: wgpu::BindGroupLayout,
    morph: wgpu::ComputePipeline,
}

/// The GPU buffers of one skinned mesh.
pub struct SkinBuffers {
    params: wgpu::Buffer,
    /// The rest vertices ([`GpuSkinVertex`]), rewritten when a keyed blend zone brings other
    /// bones-blending bindings or morph-target weights bring other rest positions
    /// ([`GpuSkinner::write_bindings`]).
    vertices: wgpu::Buffer,
    /// The rest vertices as uploaded, and the keyed bindings and morphed rest positions now
    /// written over them (`None`: as uploaded).
    rest: Vec<GpuSkinVertex>,
    written: std::sync::Mutex<Written>,
    joints: wgpu::Buffer,
    /// The skinned output: [`SkinnedVertex`] per vertex; usable as a vertex buffer.
    pub output: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pub vertex_count: u32,
    pub joint_count: u32,
}

/// The keyed bindings and the morphed rest vertices written over a skinned mesh's rest vertices.
type Written = (Option<std::sync::Arc<MeshBindings>>, Option<std::sync::Arc<[SkinnedVertex]>>);

/// The GPU buffers of one morphing (MD2) mesh.
pub struct MorphBuffers {
    params: wgpu::Buffer,
    /// The morphed output: [`SkinnedVertex`] per vertex; usable as a vertex buffer.
    pub output: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pub vertex_count: u32,
    pub frame_count: u32,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn output_buffer(device: &wgpu::Device, label: &str, vertex_count: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: vertex_count as u64 * SKINNED_VERTEX_BYTES,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

pub(crate) fn buffer_init(
    device: &wgpu::Device,
    label: &str,
    bytes: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage,
    })
}

impl GpuSkinner {
    /// Compiles the compute shaders.
    #[must_use]
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("keyrig skin.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/skin.wgsl").into()),
        });
        let skin_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("keyrig skin"),
            entries: &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("keyrig skin"),
            bind_group_layouts: &[Some(&skin_layout)],
            immediate_size: 0,
        });
        let make = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            })
        };
        let rigid = make("skin_rigid");
        let linear = make("skin_linear");
        let bones_blending = make("skin_bones_blending");
        let dual_quaternion = make("skin_dual_quaternion");

        let morph_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("keyrig morph.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/morph.wgsl").into()),
        });
        let morph_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("keyrig morph"),
            entries: &[uniform_entry(0), storage_entry(1, true), storage_entry(2, false)],
        });
        let morph_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("keyrig morph"),
            bind_group_layouts: &[Some(&morph_layout)],
            immediate_size: 0,
        });
        let morph = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("morph"),
            layout: Some(&morph_pipeline_layout),
            module: &morph_module,
            entry_point: Some("morph"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            cache: None,
        });
        GpuSkinner { skin_layout, rigid, linear, bones_blending, dual_quaternion, morph_layout, morph }
    }

    /// Validates and uploads a skinned mesh's rest data; the output starts zeroed until the
    /// first [`GpuSkinner::encode`].
    ///
    /// # Errors
    /// What [`SkinMeshInput::validate`] finds.
    pub fn create_skin(
        &self,
        device: &wgpu::Device,
        input: &SkinMeshInput<'_>,
    ) -> Result<SkinBuffers, RenderError> {
        input.validate()?;
        let vertex_count = input.positions.len();
        let joint_count = input.bind_from_model.len();
        let params = buffer_init(
            device,
            "keyrig skin params",
            bytemuck::cast_slice(&[vertex_count as u32, joint_count as u32, 0, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let rest = input.gpu_vertices();
        let vertices = buffer_init(
            device,
            "keyrig skin vertices",
            bytemuck::cast_slice(&rest),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let identity = JointPose::from_rigid(Mat4::IDENTITY, Mat4::IDENTITY, Quat::IDENTITY).to_gpu();
        let joints = buffer_init(
            device,
            "keyrig skin joints",
            bytemuck::cast_slice(&vec![identity; joint_count]),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let binds: Vec<[[f32; 4]; 4]> = input.bind_from_model.iter().map(Mat4::to_cols_array_2d).collect();
        let bind_from_model = buffer_init(
            device,
            "keyrig skin bind_from_model",
            bytemuck::cast_slice(&binds),
            wgpu::BufferUsages::STORAGE,
        );
        let output = output_buffer(device, "keyrig skinned vertices", vertex_count);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("keyrig skin"),
            layout: &self.skin_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: vertices.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: joints.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: bind_from_model.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: output.as_entire_binding() },
            ],
        });
        Ok(SkinBuffers {
            params,
            vertices,
            rest,
            written: std::sync::Mutex::new((None, None)),
            joints,
            output,
            bind_group,
            vertex_count: vertex_count as u32,
            joint_count: joint_count as u32,
        })
    }

    /// Writes one frame's joint data; returns the number of bytes uploaded.
    ///
    /// # Errors
    /// [`RenderError::JointCountMismatch`] when `poses` does not have one entry per joint,
    /// [`RenderError::NonFinite`] for NaN/infinite transforms.
    pub fn write_joints(
        &self,
        queue: &wgpu::Queue,
        skin: &SkinBuffers,
        mesh_id: u64,
        poses: &[JointPose],
    ) -> Result<u64, RenderError> {
        if poses.len() != skin.joint_count as usize {
            return Err(RenderError::JointCountMismatch {
                mesh: mesh_id,
                expected: skin.joint_count as usize,
                actual: poses.len(),
            });
        }
        for (index, pose) in poses.iter().enumerate() {
            if !pose.model_from_bind.is_finite()
                || !pose.blend_base.is_finite()
                || !pose.local_rotation.is_finite()
                || !pose.normal_from_bind.is_finite()
            {
                return Err(RenderError::NonFinite { what: "joint pose", index });
            }
        }
        let frames: Vec<GpuJointFrame> = poses.iter().map(JointPose::to_gpu).collect();
        let bytes: &[u8] = bytemuck::cast_slice(&frames);
        queue.write_buffer(&skin.joints, 0, bytes);
        Ok(bytes.len() as u64)
    }

    /// Writes the bones-blending bindings of a keyed blend zone and the morphed rest positions
    /// and normals of morph-target weights (glTF) over `skin`'s rest vertices (`None`: as
    /// uploaded) unless they are there already (the same shared values); returns the number of
    /// bytes uploaded.
    ///
    /// # Errors
    /// [`RenderError::BadCount`] when the bindings or morphed vertices are not one per vertex
    /// or a binding names a joint the mesh does not have, [`RenderError::NonFinite`] for a
    /// non-finite blend parameter or morphed vertex.
    pub fn write_bindings(
        &self,
        queue: &wgpu::Queue,
        skin: &SkinBuffers,
        mesh_id: u64,
        bindings: Option<&std::sync::Arc<MeshBindings>>,
        morph: Option<&std::sync::Arc<[SkinnedVertex]>>,
    ) -> Result<u64, RenderError> {
        let mut written = skin.written.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let same_bindings = match (written.0.as_ref(), bindings) {
            (None, None) => true,
            (Some(a), Some(b)) => std::sync::Arc::ptr_eq(a, b),
            _ => false,
        };
        let same_morph = match (written.1.as_ref(), morph) {
            (None, None) => true,
            (Some(a), Some(b)) => std::sync::Arc::ptr_eq(a, b),
            _ => false,
        };
        if same_bindings && same_morph {
            return Ok(0);
        }
        let mut vertices = skin.rest.clone();
        if let Some(morph) = morph {
            if morph.len() != vertices.len() {
                return Err(RenderError::BadCount(format!(
                    "mesh {mesh_id}: {} morphed vertices for {} vertices",
                    morph.len(),
                    vertices.len()
                )));
            }
            for (index, (vertex, m)) in vertices.iter_mut().zip(morph.iter()).enumerate() {
                if !(m.position().is_finite() && m.normal().is_finite()) {
                    return Err(RenderError::NonFinite { what: "morphed vertex", index });
                }
                vertex.position = m.position;
                vertex.normal = m.normal;
            }
        }
        if let Some(bindings) = bindings {
            let blend = &bindings.bones_blending;
            if blend.len() != vertices.len() {
                return Err(RenderError::BadCount(format!(
                    "mesh {mesh_id}: {} bones-blending bindings for {} vertices",
                    blend.len(),
                    vertices.len()
                )));
            }
            for (index, (vertex, b)) in vertices.iter_mut().zip(blend.iter()).enumerate() {
                if b.joint >= skin.joint_count {
                    return Err(RenderError::BadCount(format!(
                        "mesh {mesh_id}: vertex {index} blends at joint {} of {}",
                        b.joint, skin.joint_count
                    )));
                }
                if !b.t.is_finite() {
                    return Err(RenderError::NonFinite { what: "blend.t", index });
                }
                vertex.blend_joint = b.joint;
                vertex.blend_t = b.t.clamp(0.0, 1.0);
            }
        }
        let bytes: &[u8] = bytemuck::cast_slice(&vertices);
        queue.write_buffer(&skin.vertices, 0, bytes);
        *written = (bindings.cloned(), morph.cloned());
        Ok(bytes.len() as u64)
    }

    /// Records the compute pass of `deformer` for `skin`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, skin: &SkinBuffers, deformer: DeformerKind) {
        let pipeline = match deformer {
            DeformerKind::Rigid => &self.rigid,
            DeformerKind::LinearBlend => &self.linear,
            DeformerKind::BonesBlending => &self.bones_blending,
            DeformerKind::DualQuaternion => &self.dual_quaternion,
        };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("keyrig skin"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &skin.bind_group, &[]);
        pass.dispatch_workgroups(skin.vertex_count.div_ceil(WORKGROUP_SIZE), 1, 1);
        // Keep the params buffer referenced alongside the bind group.
        let _ = &skin.params;
    }

    /// Uploads all frames of a morphing mesh (frame-major: `frames[f][i]`).
    ///
    /// # Errors
    /// [`RenderError::BadCount`] for no frames, no vertices or frames of unequal length;
    /// [`RenderError::NonFinite`] for NaN/infinite data.
    pub fn create_morph(
        &self,
        device: &wgpu::Device,
        frames: &[Vec<SkinnedVertex>],
    ) -> Result<MorphBuffers, RenderError> {
        let Some(first) = frames.first() else {
            return Err(RenderError::BadCount("a morphing mesh needs at least one frame".into()));
        };
        let vertex_count = first.len();
        if vertex_count == 0 {
            return Err(RenderError::BadCount("a morphing mesh needs at least one vertex".into()));
        }
        check_dispatch(vertex_count)?;
        let mut all = Vec::with_capacity(vertex_count * frames.len());
        for (f, frame) in frames.iter().enumerate() {
            if frame.len() != vertex_count {
                return Err(RenderError::BadCount(format!(
                    "morph frame {f} has {} vertices, frame 0 has {vertex_count}",
                    frame.len()
                )));
            }
            if let Some(i) = frame.iter().position(|v| !v.position().is_finite() || !v.normal().is_finite()) {
                return Err(RenderError::NonFinite {
                    what: "morph frame vertex",
                    index: f * vertex_count + i,
                });
            }
            all.extend_from_slice(frame);
        }
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("keyrig morph params"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frames_buffer = buffer_init(
            device,
            "keyrig morph frames",
            bytemuck::cast_slice(&all),
            wgpu::BufferUsages::STORAGE,
        );
        let output = output_buffer(device, "keyrig morphed vertices", vertex_count);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("keyrig morph"),
            layout: &self.morph_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: frames_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: output.as_entire_binding() },
            ],
        });
        Ok(MorphBuffers {
            params,
            output,
            bind_group,
            vertex_count: vertex_count as u32,
            frame_count: frames.len() as u32,
        })
    }

    /// Sets which two frames to interpolate and the fraction t (0 = frame a, 1 = frame b);
    /// returns the bytes uploaded (16).
    ///
    /// # Errors
    /// [`RenderError::MorphFrameOutOfRange`] or [`RenderError::NonFinite`] for a bad t.
    pub fn write_morph(
        &self,
        queue: &wgpu::Queue,
        morph: &MorphBuffers,
        mesh_id: u64,
        frame_a: u32,
        frame_b: u32,
        t: f32,
    ) -> Result<u64, RenderError> {
        for frame in [frame_a, frame_b] {
            if frame >= morph.frame_count {
                return Err(RenderError::MorphFrameOutOfRange {
                    mesh: mesh_id,
                    frame,
                    frame_count: morph.frame_count,
                });
            }
        }
        if !t.is_finite() {
            return Err(RenderError::NonFinite { what: "morph t", index: 0 });
        }
        let words = [morph.vertex_count, frame_a, frame_b, t.clamp(0.0, 1.0).to_bits()];
        queue.write_buffer(&morph.params, 0, bytemuck::cast_slice(&words));
        Ok(16)
    }

    /// Records the morph compute pass.
    pub fn encode_morph(&self, encoder: &mut wgpu::CommandEncoder, morph: &MorphBuffers) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("keyrig morph"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.morph);
        pass.set_bind_group(0, &morph.bind_group, &[]);
        pass.dispatch_workgroups(morph.vertex_count.div_ceil(WORKGROUP_SIZE), 1, 1);
    }
}

/// Reads a skinned/morphed output buffer back (for tests and `keyrig` checks).
///
/// # Errors
/// [`RenderError::Gpu`] when mapping fails.
pub fn read_skinned(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    output: &wgpu::Buffer,
    vertex_count: u32,
) -> Result<Vec<SkinnedVertex>, RenderError> {
    let bytes =
        crate::gpu::read_buffer(device, queue, output, u64::from(vertex_count) * SKINNED_VERTEX_BYTES)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_struct_sizes_match_wgsl() {
        assert_eq!(SKIN_VERTEX_BYTES, 80);
        assert_eq!(JOINT_FRAME_BYTES, 240);
        assert_eq!(SKINNED_VERTEX_BYTES, 32);
    }

    #[test]
    fn dual_quaternion_reproduces_the_rigid_transform() {
        let m = Mat4::from_rotation_translation(
            Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 1.3),
            Vec3::new(0.5, -2.0, 7.0),
        );
        let (real, dual) = dual_quaternion_from_rigid(&m);
        let dual = Quat::from_array(dual);
        // translation = 2·dual·conj(real)
        let t = (dual * real.conjugate()) * 2.0;
        let p = Vec3::new(0.3, -0.4, 1.1);
        let expected = m.transform_point3(p);
        let got = real * p + Vec3::new(t.x, t.y, t.z);
        assert!((got - expected).length() < 1e-5, "{got} vs {expected}");
    }

    #[test]
    fn validate_names_the_bad_vertex() {
        let positions = [Vec3::ZERO, Vec3::X];
        let normals = [Vec3::Y, Vec3::Y];
        let joints = [[0, 0, 0, 0], [5, 0, 0, 0]];
        let weights = [[1.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]];
        let rigid = [0, 0];
        let blend = [BlendBinding { joint: 0, t: 0.0 }; 2];
        let binds = [Mat4::IDENTITY];
        let input = SkinMeshInput {
            positions: &positions,
            normals: &normals,
            joints: &joints,
            weights: &weights,
            rigid_joints: &rigid,
            blend: &blend,
            bind_from_model: &binds,
        };
        let err = input.validate().unwrap_err();
        assert!(matches!(err, RenderError::JointOutOfRange { vertex: 1, joint: 5, joint_count: 1 }), "{err}");

        let bad_weights = [[1.0, 0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0, 0.0]];
        let joints_ok = [[0, 0, 0, 0]; 2];
        let input = SkinMeshInput { weights: &bad_weights, joints: &joints_ok, ..input };
        assert!(matches!(input.validate(), Err(RenderError::BadWeights { vertex: 1, .. })));

        let short = [Vec3::Y];
        let input = SkinMeshInput { weights: &weights, normals: &short, ..input };
        assert!(matches!(
            input.validate(),
            Err(RenderError::LengthMismatch { field: "normals", expected: 2, actual: 1 })
        ));
    }
}
